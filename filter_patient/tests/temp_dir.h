// Test helpers of the patient core: a temporary folder for a test's files (removed with everything in it
// when the test ends) and the message of the InputError a call throws.
#pragma once
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>
#include <string>

#include "pectus/errors.h"

namespace pectus::patient::testing {

struct TempDir {
  std::filesystem::path p;
  explicit TempDir(const std::string& prefix = "pectus-test-") {
    std::random_device rd;
    p = std::filesystem::temp_directory_path() / (prefix + std::to_string(rd()) + std::to_string(rd()));
    std::filesystem::create_directories(p);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(p, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  std::string path(const std::string& name) const { return (p / name).string(); }
  /// writes `content` to the file `name` in the folder and returns its path
  std::string file(const std::string& name, const std::string& content) const {
    std::ofstream(p / name, std::ios::binary) << content;
    return path(name);
  }
};

/// the message of the InputError f throws, or "(no InputError)"
inline std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const pectus::InputError& e) {
    return e.what();
  }
  return "(no InputError)";
}

}  // namespace pectus::patient::testing
