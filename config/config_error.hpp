#pragma once
// The error of every strict reader of configuration (config/strict_yaml.hpp): what() reads
// "file:line: reason". Apart from the YAML reader, so that code which only throws or catches it
// does not compile yaml-cpp.

#include <stdexcept>
#include <string>

namespace shelfcross::config {

class ConfigError : public std::runtime_error {
 public:
  ConfigError(std::string file, int line, std::string reason);
  const std::string& file() const { return file_; }
  int line() const { return line_; }  ///< 1-based; 0 when the problem has no line
  const std::string& reason() const { return reason_; }

 private:
  std::string file_;
  int line_;
  std::string reason_;
};

}  // namespace shelfcross::config
