// fuzz_tree_file.cpp — libFuzzer target for parse_tree_file, the reader of `kdray build -o` files.
// The input is a file's body; the target appends the checksum the body would need, so that the
// fuzzer reaches the checks behind it (parameters, offsets, leaf indices) instead of stopping at
// a checksum that random bytes never match. kdray::Error is the expected outcome of a bad file; a
// sanitizer report, another exception, or an accepted tree that breaks its invariants is a bug.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "core/error.h"
#include "core/tree/tree_check.h"
#include "core/tree/tree_file.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    std::string bytes(reinterpret_cast<const char*>(data), size);
    const std::uint64_t checksum = kdray::tree_file_checksum(bytes);
    bytes.append(reinterpret_cast<const char*>(&checksum), sizeof(checksum));
    try {
        const kdray::TreeFile file = kdray::parse_tree_file(bytes, "fuzz.kdt");
        // Accepted: every index must be in range, so that a renderer can walk it safely.
        if (!kdray::check_tree_layout(file.tree, file.scene_triangles, 1).empty()) {
            std::fprintf(stderr, "fuzz_tree_file: accepted a tree with a broken layout\n");
            std::abort();
        }
    } catch (const kdray::Error&) {
    }
    return 0;
}
