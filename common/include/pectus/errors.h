#pragma once
#include <stdexcept>
#include <string>

namespace pectus {
/// Bad input or parameters: the message is written for the user (it names what to fix).
class InputError : public std::runtime_error {
 public:
  explicit InputError(const std::string& what) : std::runtime_error(what) {}
};
}  // namespace pectus
