// kdray — builds kd-trees over triangle scenes on an OpenCL device and ray traces them.
// This file parses the command line, dispatches to the commands, and is the one place errors are
// caught: `kdray: error: ...` on stderr, exit status 2 for usage errors and 1 for everything else.
#include <CLI/CLI.hpp>

#include <exception>
#include <iostream>

#include "core/error.h"

int main(int argc, char** argv) {
    CLI::App app{"kdray: kd-trees built on an OpenCL device (Zhou et al. 2008), ray traced"};
    app.require_subcommand(1);
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        return app.exit(e);
    }
    return 0;
}
