// inputs.h — the frames of a run: files or glob patterns, expanded and put in natural order
// (frame_2 before frame_10), since a frame's number is its position in that order (conventions.md).
#pragma once

#include <string>
#include <vector>

namespace kdray::cli {

/// Throws UsageError when `path` is plainly not an OBJ scene: a render file (JSON), or another
/// scene format (PLY, glTF, FBX, STL, USD, ...) or a compressed OBJ, saying what to do instead.
void check_scene_input(const std::string& path);

/// Expands glob patterns that the shell left alone, checks every file exists, sorts naturally
/// and drops duplicates; each file passes check_scene_input. Throws Error naming a missing file or
/// a pattern that matched nothing.
std::vector<std::string> expand_inputs(const std::vector<std::string>& arguments);

}  // namespace kdray::cli
