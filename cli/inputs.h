// inputs.h — the frames of a run: files or glob patterns, expanded and put in natural order
// (frame_2 before frame_10), since a frame's number is its position in that order (conventions.md).
#pragma once

#include <string>
#include <vector>

namespace kdray::cli {

/// Expands glob patterns that the shell left alone, checks every file exists, sorts naturally
/// and drops duplicates. Throws Error naming a missing file or a pattern that matched nothing.
std::vector<std::string> expand_inputs(const std::vector<std::string>& arguments);

}  // namespace kdray::cli
