// Error types of the core. Every failure the user can cause is one of these, with a message that names the
// file, field or value at fault; the Python binding maps them one to one (see native/python/module.cpp).
#pragma once
#include <stdexcept>
#include <string>

namespace meniscus {

// A parameter or an input array is invalid (wrong value, NaN positions, ...). Python: ValueError.
class InputError : public std::invalid_argument {
public:
    explicit InputError(const std::string& message) : std::invalid_argument(message) {}
};

// A file cannot be read or parsed. The message starts with the file path. Python: meniscus.FormatError (ValueError).
class FormatError : public std::runtime_error {
public:
    explicit FormatError(const std::string& message) : std::runtime_error(message) {}
};

// The work would need more memory than the budget allows; the message carries the estimate. Python: MemoryError.
class ResourceError : public std::runtime_error {
public:
    explicit ResourceError(const std::string& message) : std::runtime_error(message) {}
};

}  // namespace meniscus
