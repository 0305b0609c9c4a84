// warning_tally.h — a run's warnings, each cause once. Every frame of an animation that shares an
// MTL repeats its warnings (Sponza's 20 per frame made ~5,700 lines for 100 frames), each beginning
// with the frame's own OBJ file: a cause is the warning without that prefix, printed the first
// time it is seen and counted after that. The run's record in stats.json lists each cause with
// its count; the log ends with one summary line (cli/cmd_render.cpp).
#pragma once

#include <cstddef>
#include <map>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/error.h"

namespace kdray {

class WarningTally {
  public:
    /// Counts `text`, a warning of frame `frame` whose input is `input`; true the first time its
    /// cause (`text` less a leading "`input`:") is seen, when it is to be printed.
    bool add(std::size_t frame, std::string_view input, const std::string& text);

    std::size_t total() const { return total_; }
    std::size_t kinds() const { return causes_.size(); }
    /// The frames with at least one warning.
    std::size_t frames() const { return frames_.size(); }

    /// The causes in the order first seen: [{"warning": the first text, "count": frames that gave
    /// it, "first_frame": the first of them}], stats.json's run "warnings".
    nlohmann::json to_json() const;

    /// "23 warnings (3 kinds) in 12 frames; each printed once"; empty when nothing was warned.
    std::string summary() const;

  private:
    struct Cause {
        std::string first_text;
        std::size_t count = 0, first_frame = 0;
    };
    std::map<std::string, std::size_t> index_;  // cause -> position in causes_
    std::vector<Cause> causes_;
    std::set<std::size_t> frames_;
    std::size_t total_ = 0;
};

/// --strict: `warnings` (what a scene or a tree warned) as the Error that fails the run, naming
/// the first and how many more; does nothing when there are none.
void throw_if_strict(bool strict, const std::vector<std::string>& warnings);

}  // namespace kdray
