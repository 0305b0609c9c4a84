#include "core/io/output_name.h"

#include <filesystem>
#include <utility>

#include "core/error.h"

namespace kdray {
namespace {

/// `pattern` with its placeholders replaced; throws UsageError on a bad pattern.
std::string expand(const std::string& pattern, const std::string& stem, std::size_t frame) {
    auto bad = [&](const std::string& why) {
        return UsageError("--name '" + pattern + "': " + why +
                          " (placeholders: {stem}, {frame}, {frame:04})");
    };
    std::string name;
    for (std::size_t i = 0; i < pattern.size(); ++i) {
        const char c = pattern[i];
        if (c == '/' || c == '\\') throw bad("a name cannot hold a path separator");
        if (c == '}') throw bad("a '}' without its '{'");
        if (c != '{') {
            name += c;
            continue;
        }
        const std::size_t close = pattern.find('}', i);
        if (close == std::string::npos) throw bad("a '{' without its '}'");
        const std::string field = pattern.substr(i + 1, close - i - 1);
        if (field == "stem") {
            name += stem;
        } else if (field == "frame") {
            name += std::to_string(frame);
        } else if (field.size() == 8 && field.compare(0, 7, "frame:0") == 0 && field[7] >= '1' &&
                   field[7] <= '9') {
            const std::string digits = std::to_string(frame);
            const std::size_t width = std::size_t(field[7] - '0');
            name += std::string(digits.size() < width ? width - digits.size() : 0, '0') + digits;
        } else {
            throw bad("unknown placeholder {" + field + "}");
        }
        i = close;
    }
    if (name.empty()) throw bad("the name is empty");
    // A hidden name would read as one of kdray's temporaries (.NAME.kdray.tmp@HOST@PID@RANDOM),
    // which a later run into the folder removes.
    if (name[0] == '.') throw bad("a name cannot start with '.'");
    return name;
}

}  // namespace

OutputName::OutputName(std::string pattern) : pattern_(std::move(pattern)) {
    expand(pattern_, "stem", 0);  // throws on a bad pattern before any frame renders
}

std::string OutputName::operator()(const std::string& input, std::size_t frame) const {
    const std::string stem = std::filesystem::path(input).stem().string();
    return expand(pattern_, stem, frame);
}

}  // namespace kdray
