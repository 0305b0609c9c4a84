#include "cli/frame_selection.h"

#include <algorithm>
#include <charconv>
#include <optional>

#include "core/error.h"

namespace kdray::cli {
namespace {

std::optional<long long> parse_number(const std::string& text) {
    long long value = 0;
    auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
    if (ec != std::errc() || end != text.data() + text.size()) return std::nullopt;
    return value;
}

std::vector<std::string> split(const std::string& text, char separator) {
    std::vector<std::string> parts(1);
    for (char c : text) {
        if (c == separator)
            parts.emplace_back();
        else
            parts.back() += c;
    }
    return parts;
}

}  // namespace

std::vector<std::size_t> select_frames(std::size_t count, const std::string& frames,
                                       const std::string& shard) {
    long long first = 0, last = static_cast<long long>(count) - 1, step = 1;
    if (!frames.empty()) {
        std::vector<std::string> parts = split(frames, ':');
        auto bad = [&] {
            return UsageError("--frames " + frames +
                              ": expected START:END[:STEP] with whole numbers, END included");
        };
        if (parts.size() < 2 || parts.size() > 3) throw bad();
        if (!parts[0].empty()) first = parse_number(parts[0]).value_or(-1);
        if (!parts[1].empty()) last = parse_number(parts[1]).value_or(-2);
        if (parts.size() == 3) step = parse_number(parts[2]).value_or(0);
        if (first < 0 || last < -1 || step < 1) throw bad();
    }
    long long shard_index = 0, shard_count = 1;
    if (!shard.empty()) {
        std::vector<std::string> parts = split(shard, '/');
        if (parts.size() == 2) {
            shard_index = parse_number(parts[0]).value_or(-1);
            shard_count = parse_number(parts[1]).value_or(0);
        }
        if (parts.size() != 2 || shard_count < 1 || shard_index < 0 || shard_index >= shard_count)
            throw UsageError("--shard " + shard + ": expected I/N with 0 <= I < N");
    }
    std::vector<std::size_t> selected;
    // The last frame that exists and was asked for; the step is taken only while it stays at or
    // below it, so that a step near 2^63 ends the range instead of overflowing into a negative
    // frame (exit 139, or a frame number of 2^64 - N).
    const long long end = std::min(last, static_cast<long long>(count) - 1);
    long long position = 0;  // among the frames --frames picked
    for (long long f = first; f <= end; ++position) {
        if (position % shard_count == shard_index) selected.push_back(static_cast<std::size_t>(f));
        if (step > end - f) break;
        f += step;
    }
    return selected;
}

}  // namespace kdray::cli
