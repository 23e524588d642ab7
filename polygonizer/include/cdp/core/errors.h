// Typed errors of the library. Messages are one line and name the file or object at fault.
#pragma once

#include <stdexcept>
#include <string>

namespace cdp {

// Malformed configuration: bad JSON, unknown or misspelled keys, wrong types, missing files.
class InvalidInputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A file that cannot be opened, read or written (missing, a folder, no permission, a full disk).
// Still an InvalidInputError to every caller that does not care; the Python bindings raise
// OSError for it instead of ValueError. `error_number` is the errno behind it (0 when none).
class FileError : public InvalidInputError {
 public:
  FileError(const std::string& message, int error_number) : InvalidInputError(message), error_number_(error_number) {}
  int error_number() const { return error_number_; }

 private:
  int error_number_ = 0;
};

// The field has no usable surface: no zero crossing in its box, a surface leaving the box,
// NaN values, or a vanishing gradient where a surface point was expected.
class NoSurfaceError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// An algorithm hit one of its bounds (steps, triangles, iterations) before finishing.
class LimitExceededError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace cdp
