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
                                       const std::string& shard, std::string* past) {
    long long first = 0, last = static_cast<long long>(count) - 1, step = 1;
    bool end_given = false;
    if (!frames.empty()) {
        auto bad = [&] {
            return UsageError("--frames " + frames +
                              ": expected START:END[:STEP] with whole numbers, END included, or "
                              "N (one frame) or START-END");
        };
        // One frame (`5`) and a dash range (`2-4`), as users of Blender and print dialogs write
        // them, beside kdray's own START:END.
        std::vector<std::string> parts = split(frames, ':');
        if (parts.size() == 1) {
            parts = split(frames, '-');
            if (parts.size() == 1) parts.push_back(parts[0]);
            if (parts.size() != 2 || parts[0].empty() || parts[1].empty()) throw bad();
        }
        if (parts.size() < 2 || parts.size() > 3) throw bad();
        if (!parts[0].empty()) first = parse_number(parts[0]).value_or(-1);
        if (!parts[1].empty()) last = parse_number(parts[1]).value_or(-2);
        end_given = !parts[1].empty();
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
    if (past) past->clear();
    const long long n = static_cast<long long>(count);
    // A range that reaches past the inputs is rendered as far as they go, and said: `--frames
    // 9:12` on 10 inputs rendered frame 9 without a word. A range wholly past them selects
    // nothing, which the caller refuses.
    if (past && end_given && last >= n && first < n) {
        // Counted in steps, never as first + k * step past `last`: a step near 2^63 overflows.
        const long long steps = (last - first) / step, steps_in = (n - 1 - first) / step;
        if (steps_in < steps) {
            const long long in_last = first + steps_in * step;
            const long long past_first = in_last + step, past_last = first + steps * step;
            *past = "--frames " + frames + ": " +
                    (past_first == past_last ? "frame " + std::to_string(past_first) + " is"
                                             : "frames " + std::to_string(past_first) + " to " +
                                                   std::to_string(past_last) + " are") +
                    " past the " + std::to_string(count) + " inputs; rendering " +
                    (in_last == first
                         ? "frame " + std::to_string(first)
                         : "frames " + std::to_string(first) + " to " + std::to_string(in_last));
        }
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
