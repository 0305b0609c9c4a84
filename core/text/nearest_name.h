// nearest_name.h — "did you mean ...?" for a mistyped name: the command line's commands and
// options (cli/main.cpp) and the render file's fields (core/render/render_file.cpp) share it.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace kdray {

/// Levenshtein distance: insertions, deletions and substitutions of one byte each.
std::size_t edit_distance(std::string_view a, std::string_view b);

/// "; did you mean 'NAME'?" with the name of `names` nearest to `given`, or "" when none is near
/// (at most 2 edits, or a third of the name): `max_dpeth` gets `max_depth`, `size` nothing.
std::string did_you_mean(std::string_view given, const std::vector<std::string>& names);

}  // namespace kdray
