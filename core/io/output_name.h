// output_name.h — the name a frame's files get in the output folder: the OBJ's stem by default,
// or `kdray render --name PATTERN` (e.g. "frame_{frame:04}", "{stem}_lit"), whose image is
// NAME.png and whose AOV NAME.aov.exr.
#pragma once

#include <cstddef>
#include <string>

namespace kdray {

/// A checked --name pattern. Placeholders: {stem} (the input's file name without its extension),
/// {frame} (the frame number: the input's position in the naturally sorted inputs) and
/// {frame:0N} (zero-padded to N digits, N from 1 to 9). Throws UsageError naming the pattern for
/// an unknown or unclosed placeholder, a path separator, an empty name or one starting with '.'.
class OutputName {
  public:
    explicit OutputName(std::string pattern = "{stem}");

    /// The name of frame `frame`, read from `input` (a path).
    std::string operator()(const std::string& input, std::size_t frame) const;

    const std::string& pattern() const { return pattern_; }

  private:
    std::string pattern_;
};

}  // namespace kdray
