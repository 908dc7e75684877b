#include "base/platform.h"

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <vector>

#ifdef _WIN32
#ifndef WIN32_LEAN_AND_MEAN
#define WIN32_LEAN_AND_MEAN
#endif
#ifndef NOMINMAX
#define NOMINMAX
#endif
#include <windows.h>
#include <fcntl.h>
#include <io.h>
#include <psapi.h>
#include <shellapi.h>
#elif defined(__APPLE__)
#include <signal.h>
#include <sys/resource.h>
#include <sys/sysctl.h>
#include <sys/types.h>
#include <unistd.h>
#else
#include <signal.h>
#include <sys/resource.h>
#include <unistd.h>
#endif

namespace meniscus {

#ifdef _WIN32
namespace {

std::wstring widen(const std::string& utf8) {
    if (utf8.empty()) return {};
    const int size = MultiByteToWideChar(CP_UTF8, 0, utf8.data(), static_cast<int>(utf8.size()), nullptr, 0);
    std::wstring wide(static_cast<std::size_t>(size > 0 ? size : 0), L'\0');
    if (size > 0) MultiByteToWideChar(CP_UTF8, 0, utf8.data(), static_cast<int>(utf8.size()), wide.data(), size);
    return wide;
}

std::string narrow(const wchar_t* wide, int length) {
    if (length == 0) return {};
    const int size = WideCharToMultiByte(CP_UTF8, 0, wide, length, nullptr, 0, nullptr, nullptr);
    std::string utf8(static_cast<std::size_t>(size > 0 ? size : 0), '\0');
    if (size > 0) WideCharToMultiByte(CP_UTF8, 0, wide, length, utf8.data(), size, nullptr, nullptr);
    return utf8;
}

}  // namespace
#endif

std::filesystem::path path_from_utf8(const std::string& utf8) {
#ifdef _WIN32
    return std::filesystem::path(widen(utf8));
#else
    return std::filesystem::path(utf8);
#endif
}

std::string path_to_utf8(const std::filesystem::path& path) {
#ifdef _WIN32
    const std::wstring& wide = path.native();
    return narrow(wide.data(), static_cast<int>(wide.size()));
#else
    return path.native();
#endif
}

std::FILE* open_file(const std::string& utf8_path, const char* mode) {
#ifdef _WIN32
    if (std::string(mode) != "rb") return _wfopen(widen(utf8_path).c_str(), widen(mode).c_str());
    // The C runtime's fopen shares read and write access only: a writer replacing the file would fail.
    HANDLE handle = CreateFileW(widen(utf8_path).c_str(), GENERIC_READ, FILE_SHARE_READ | FILE_SHARE_WRITE | FILE_SHARE_DELETE,
                                nullptr, OPEN_EXISTING, FILE_ATTRIBUTE_NORMAL, nullptr);
    if (handle == INVALID_HANDLE_VALUE) {
        const DWORD code = GetLastError();
        errno = (code == ERROR_FILE_NOT_FOUND || code == ERROR_PATH_NOT_FOUND) ? ENOENT
                : (code == ERROR_ACCESS_DENIED || code == ERROR_SHARING_VIOLATION) ? EACCES : EIO;
        return nullptr;
    }
    const int descriptor = _open_osfhandle(reinterpret_cast<intptr_t>(handle), _O_RDONLY | _O_BINARY);
    if (descriptor == -1) {
        CloseHandle(handle);
        return nullptr;
    }
    std::FILE* file = _fdopen(descriptor, "rb");
    if (!file) _close(descriptor);
    return file;
#else
    return std::fopen(utf8_path.c_str(), mode);
#endif
}

#ifdef _WIN32
namespace {

// Windows 10 1809+ on NTFS: a rename with POSIX semantics replaces a target that readers hold open while sharing
// delete access (they keep the old file). Fails elsewhere (older systems, Wine: ERROR_INVALID_PARAMETER).
bool rename_posix(const std::wstring& from, const std::wstring& to) {
    HANDLE source = CreateFileW(from.c_str(), DELETE, FILE_SHARE_READ | FILE_SHARE_WRITE | FILE_SHARE_DELETE, nullptr,
                                OPEN_EXISTING, FILE_ATTRIBUTE_NORMAL, nullptr);
    if (source == INVALID_HANDLE_VALUE) return false;
    const DWORD name_bytes = static_cast<DWORD>(to.size() * sizeof(wchar_t));
    std::vector<unsigned char> buffer(sizeof(FILE_RENAME_INFO) + name_bytes);
    auto* info = reinterpret_cast<FILE_RENAME_INFO*>(buffer.data());
    // The first member is a BOOLEAN in old headers and a union with DWORD Flags in new ones: write the flags
    // (FILE_RENAME_FLAG_REPLACE_IF_EXISTS | FILE_RENAME_FLAG_POSIX_SEMANTICS) as the DWORD they are.
    const DWORD flags = 0x1 | 0x2;
    std::memcpy(buffer.data(), &flags, sizeof flags);
    info->RootDirectory = nullptr;
    info->FileNameLength = name_bytes;
    std::memcpy(info->FileName, to.data(), name_bytes);
    const auto rename_info_ex = static_cast<FILE_INFO_BY_HANDLE_CLASS>(22);  // FileRenameInfoEx
    const BOOL renamed = SetFileInformationByHandle(source, rename_info_ex, info, static_cast<DWORD>(buffer.size()));
    const DWORD code = GetLastError();
    CloseHandle(source);
    SetLastError(code);
    return renamed != 0;
}

// Classic semantics refuse to rename over an open file, but an open file whose readers share delete access may
// itself be renamed: move it aside, move the new one in, and delete the old (gone when its last reader closes it).
// For that instant the name is free: a reader opening it then finds no file (and tries again), never a partial one.
bool rename_old_aside(const std::wstring& from, const std::wstring& to) {
    const std::wstring aside = to + L".replaced-" + std::to_wstring(GetCurrentProcessId());
    if (!MoveFileExW(to.c_str(), aside.c_str(), MOVEFILE_REPLACE_EXISTING)) return false;
    if (!MoveFileExW(from.c_str(), to.c_str(), 0)) {
        MoveFileExW(aside.c_str(), to.c_str(), 0);
        return false;
    }
    DeleteFileW(aside.c_str());
    return true;
}

}  // namespace
#endif

std::string replace_file(const std::string& utf8_from, const std::string& utf8_to) {
#ifdef _WIN32
    const std::wstring from = widen(utf8_from), to = widen(utf8_to);
    for (int attempt = 0;; ++attempt) {
        if (rename_posix(from, to) || MoveFileExW(from.c_str(), to.c_str(), MOVEFILE_REPLACE_EXISTING)) return {};
        const DWORD code = GetLastError();
        const bool held = code == ERROR_ACCESS_DENIED || code == ERROR_SHARING_VIOLATION;
        if (held && rename_old_aside(from, to)) return {};
        // A reader that does not share delete access (most programs' fopen): wait for it to let go, a while.
        if (!held || attempt == 100) {
            wchar_t* text = nullptr;
            FormatMessageW(FORMAT_MESSAGE_ALLOCATE_BUFFER | FORMAT_MESSAGE_FROM_SYSTEM | FORMAT_MESSAGE_IGNORE_INSERTS,
                           nullptr, code, 0, reinterpret_cast<wchar_t*>(&text), 0, nullptr);
            std::string message = text ? narrow(text, static_cast<int>(wcslen(text))) : "error " + std::to_string(code);
            if (text) LocalFree(text);
            while (!message.empty() && (message.back() == '\n' || message.back() == '\r' || message.back() == ' ' ||
                                        message.back() == '.'))
                message.pop_back();
            return held ? message + "; another program kept the file open for 5 seconds" : message;
        }
        Sleep(50);
    }
#else
    if (std::rename(utf8_from.c_str(), utf8_to.c_str()) == 0) return {};
    return std::strerror(errno);
#endif
}

bool remove_file(const std::string& utf8_path) {
    std::error_code error;
    return std::filesystem::remove(path_from_utf8(utf8_path), error);
}

long current_process_id() {
#ifdef _WIN32
    return static_cast<long>(GetCurrentProcessId());
#else
    return static_cast<long>(getpid());
#endif
}

bool process_exists(long process_id) {
    if (process_id <= 0) return false;
    if (process_id == current_process_id()) return true;
#ifdef _WIN32
    // Signals do not exist there: a process exists while it can be opened and has not exited.
    const HANDLE process = OpenProcess(PROCESS_QUERY_LIMITED_INFORMATION, FALSE, static_cast<DWORD>(process_id));
    if (!process) return GetLastError() == ERROR_ACCESS_DENIED;  // another user's
    DWORD code = 0;
    const bool running = GetExitCodeProcess(process, &code) && code == STILL_ACTIVE;
    CloseHandle(process);
    return running;
#else
    if (kill(static_cast<pid_t>(process_id), 0) == 0) return true;
    return errno == EPERM;  // another user's
#endif
}

bool is_terminal(std::FILE* stream) {
#ifdef _WIN32
    return _isatty(_fileno(stream)) != 0;
#else
    return isatty(fileno(stream)) != 0;
#endif
}

std::vector<std::string> utf8_arguments(int argc, char** argv) {
#ifdef _WIN32
    int count = 0;
    wchar_t** wide = CommandLineToArgvW(GetCommandLineW(), &count);
    if (wide) {
        std::vector<std::string> arguments;
        for (int i = 0; i < count; ++i) arguments.push_back(narrow(wide[i], static_cast<int>(wcslen(wide[i]))));
        LocalFree(wide);
        return arguments;
    }
#endif
    return std::vector<std::string>(argv, argv + argc);
}

void use_utf8_console() {
#ifdef _WIN32
    SetConsoleOutputCP(CP_UTF8);
#endif
}

namespace {
constexpr std::size_t kUnknownPhysicalMemory = std::size_t(8) << 30;  // assume a modest 8 GiB when it cannot be read
}

std::size_t physical_memory_bytes() {
#if defined(_WIN32)
    MEMORYSTATUSEX status{};
    status.dwLength = sizeof status;
    if (!GlobalMemoryStatusEx(&status) || status.ullTotalPhys == 0) return kUnknownPhysicalMemory;
    return static_cast<std::size_t>(status.ullTotalPhys);
#elif defined(__APPLE__)
    std::uint64_t bytes = 0;
    std::size_t size = sizeof bytes;
    if (sysctlbyname("hw.memsize", &bytes, &size, nullptr, 0) != 0 || bytes == 0) return kUnknownPhysicalMemory;
    return static_cast<std::size_t>(bytes);
#else
    const long pages = sysconf(_SC_PHYS_PAGES);
    const long page_size = sysconf(_SC_PAGE_SIZE);
    if (pages <= 0 || page_size <= 0) return kUnknownPhysicalMemory;
    return static_cast<std::size_t>(pages) * static_cast<std::size_t>(page_size);
#endif
}

std::size_t peak_rss_bytes() {
#if defined(_WIN32)
    PROCESS_MEMORY_COUNTERS counters{};
    if (!GetProcessMemoryInfo(GetCurrentProcess(), &counters, sizeof counters)) return 0;
    return static_cast<std::size_t>(counters.PeakWorkingSetSize);
#else
    struct rusage usage {};
    if (getrusage(RUSAGE_SELF, &usage) != 0) return 0;
#if defined(__APPLE__)
    return static_cast<std::size_t>(usage.ru_maxrss);  // macOS reports bytes
#else
    return static_cast<std::size_t>(usage.ru_maxrss) * 1024;  // Linux and the BSDs report KiB
#endif
#endif
}

}  // namespace meniscus
