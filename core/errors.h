// Errors a user can act on. InputError is bad input (a scene, a terrain, an argument): the
// program prints its one-line message and exits with status 2. Anything else exits with 1.
#pragma once
#include <stdexcept>
#include <string>

namespace snow {

class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace snow
