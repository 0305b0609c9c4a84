#include "core/run/warning_tally.h"

namespace kdray {

bool WarningTally::add(std::size_t frame, std::string_view input, const std::string& text) {
    std::string_view cause = text;
    // Scene warnings begin "frame_0007.obj: ..." or "frame_0007.obj:12: ...": the same MTL
    // statement in every frame is one cause.
    if (!input.empty() && cause.substr(0, input.size()) == input &&
        cause.substr(input.size(), 1) == ":")
        cause.remove_prefix(input.size());
    ++total_;
    frames_.insert(frame);
    const auto [it, fresh] = index_.try_emplace(std::string(cause), causes_.size());
    if (fresh) causes_.push_back({text, 0, frame});
    ++causes_[it->second].count;
    return fresh;
}

nlohmann::json WarningTally::to_json() const {
    nlohmann::json list = nlohmann::json::array();
    for (const Cause& c : causes_)
        list.push_back(
            {{"warning", c.first_text}, {"count", c.count}, {"first_frame", c.first_frame}});
    return list;
}

std::string WarningTally::summary() const {
    if (total_ == 0) return {};
    const auto plural = [](std::size_t n, const char* word) {
        return std::to_string(n) + " " + word + (n == 1 ? "" : "s");
    };
    return plural(total_, "warning") + " (" + plural(kinds(), "kind") + ") in " +
           plural(frames(), "frame") + (total_ > kinds() ? "; each printed once" : "");
}

void throw_if_strict(bool strict, const std::vector<std::string>& warnings) {
    if (!strict || warnings.empty()) return;
    throw Error("--strict: " + warnings.front() +
                (warnings.size() > 1
                     ? " (and " + std::to_string(warnings.size() - 1) + " more warning(s))"
                     : std::string()));
}

}  // namespace kdray
