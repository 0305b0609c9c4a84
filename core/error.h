// error.h — the one exception type core/ and cl/ throw. It carries its context in the message
// (file, line, value; for OpenCL the call and the error's name), and cli/main.cpp catches it once.
#pragma once

#include <stdexcept>
#include <string>

namespace kdray {

class Error : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

/// A command line that cannot work (a missing input, a bad option value): exit status 2.
class UsageError : public Error {
public:
    using Error::Error;
};

}  // namespace kdray
