// The one exception type of the project. Its message is a single line naming the file and line
// or the cause; the CLI prints it as "clbdpt: error: <message>" and exits non-zero.
#pragma once

#include <stdexcept>
#include <string>

namespace clbdpt {

class Error : public std::runtime_error {
public:
    explicit Error(const std::string& message) : std::runtime_error(message) {}
};

}  // namespace clbdpt
