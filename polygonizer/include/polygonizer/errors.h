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
