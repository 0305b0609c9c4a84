// fuzz_scratch.h — the scratch folder of a fuzz target's process (libFuzzer's workers run side by
// side, so each has its own), in /dev/shm where there is one, removed when libFuzzer ends the run.
#pragma once

#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <string>
#include <system_error>

namespace kdray::fuzz {

/// The folder, made on first use: /dev/shm/kdray-TARGET-PID (or the temporary folder's).
inline const std::filesystem::path& scratch_folder(const char* target) {
    namespace fs = std::filesystem;
    // Never destroyed: the atexit handler below reads it after static destructors have run.
    static const fs::path& dir = *new fs::path([target] {
        const fs::path base =
            fs::exists("/dev/shm") ? fs::path("/dev/shm") : fs::temp_directory_path();
        const fs::path d =
            base / ("kdray-" + std::string(target) + "-" + std::to_string(::getpid()));
        fs::create_directories(d);
        // Gone when libFuzzer ends the run (exit); a crash leaves it, with the input that did.
        std::atexit([] {
            std::error_code ignored;
            fs::remove_all(scratch_folder(""), ignored);
        });
        return d;
    }());
    return dir;
}

}  // namespace kdray::fuzz
