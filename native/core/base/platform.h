// The few operating-system services the core needs, behind one portable interface. Paths are UTF-8 everywhere in
// Meniscus (Python hands its str over as UTF-8); Windows opens files by UTF-16 names, so a path with non-ASCII
// characters must never reach a narrow-character API there.
#pragma once
#include <cstddef>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

namespace meniscus {

// The filesystem path a UTF-8 string names, on every platform.
std::filesystem::path path_from_utf8(const std::string& utf8);
// The UTF-8 spelling of a filesystem path.
std::string path_to_utf8(const std::filesystem::path& path);
// std::fopen for a UTF-8 path (mode as for fopen); nullptr with errno set on failure. On Windows a file opened for
// reading shares delete access, so that a writer can replace it meanwhile (replace_file), as POSIX always allows.
std::FILE* open_file(const std::string& utf8_path, const char* mode);
// Renames `from` over `to` (readers see the old file or the new one, never a mix). Windows refuses a plain rename
// over a file another process has open: where its readers share delete access (the core's own), the old file is
// replaced anyway (see platform.cpp); where one does not (most programs' fopen), the rename is tried again for up to
// about 5 seconds, a reader's usual time. Returns an empty string, or why it failed.
std::string replace_file(const std::string& utf8_from, const std::string& utf8_to);
// Removes a file named by a UTF-8 path; false when it could not be removed.
bool remove_file(const std::string& utf8_path);

// This process's id, and whether a process with this id runs on this machine (another user's included).
long current_process_id();
bool process_exists(long process_id);

// Whether the stream is an interactive terminal (progress bars only draw there).
bool is_terminal(std::FILE* stream);

// The process's command-line arguments as UTF-8 (argv[0] included). On Windows argv is in the ANSI code page and
// loses characters outside it, so the arguments are taken from the wide-character command line instead.
std::vector<std::string> utf8_arguments(int argc, char** argv);
// Physical memory of the machine (8 GiB where it cannot be read) and this process's peak resident memory (0 where
// unknown): GlobalMemoryStatusEx / GetProcessMemoryInfo on Windows, sysctl and getrusage (bytes) on macOS,
// sysconf and getrusage (KiB) on Linux.
std::size_t physical_memory_bytes();
std::size_t peak_rss_bytes();

// Lets the console show UTF-8 text (file names) on Windows; nothing elsewhere.
void use_utf8_console();

}  // namespace meniscus
