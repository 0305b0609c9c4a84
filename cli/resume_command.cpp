#include "cli/resume_command.h"

#include <algorithm>
#include <cstdio>

namespace kdray::cli {
namespace {

bool is_plain(unsigned char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
           std::string_view("_@%+=:,./-").find(char(c)) != std::string_view::npos;
}

/// Whether single quotes can hold `word` as one printable line: no control characters (C0, DEL,
/// and C1, which some terminals obey: U+009B is a CSI) and nothing that is not UTF-8.
bool printable_in_quotes(std::string_view word) {
    for (std::size_t i = 0; i < word.size();) {
        const auto c = static_cast<unsigned char>(word[i]);
        if (c < 0x20 || c == 0x7f) return false;
        if (c < 0x80) {
            ++i;
            continue;
        }
        const std::size_t n = c >= 0xf5 ? 0 : c >= 0xf0 ? 4 : c >= 0xe0 ? 3 : c >= 0xc2 ? 2 : 0;
        if (n == 0 || i + n > word.size()) return false;
        for (std::size_t k = 1; k < n; ++k)
            if ((static_cast<unsigned char>(word[i + k]) & 0xc0) != 0x80) return false;
        if (c == 0xc2 && static_cast<unsigned char>(word[i + 1]) < 0xa0) return false;
        i += n;
    }
    return true;
}

}  // namespace

std::string shell_word(std::string_view word) {
    if (!word.empty() && std::all_of(word.begin(), word.end(), [](char c) {
            return is_plain(static_cast<unsigned char>(c));
        }))
        return std::string(word);
    std::string out;
    if (printable_in_quotes(word)) {
        out = "'";
        for (const char c : word) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
        return out + "'";
    }
    out = "$'";
    for (const char c : word) {
        const auto byte = static_cast<unsigned char>(c);
        if (byte < 0x20 || byte >= 0x7f || c == '\'' || c == '\\') {
            char escape[8];
            std::snprintf(escape, sizeof escape, "\\x%02x", byte);
            out += escape;
        } else {
            out += c;
        }
    }
    return out + "'";
}

std::string resume_command(const std::vector<std::string>& argv) {
    std::vector<std::string> words = argv;
    const bool skipping = std::any_of(words.begin(), words.end(), [](const std::string& w) {
        return w.rfind("--skip-existing", 0) == 0;
    });
    if (!skipping) {
        // After the subcommand, not at the end: past a `--` the option would be an input.
        auto at = words.begin() + (words.empty() ? 0 : 1);
        for (; at != words.end(); ++at)
            if (*at == "render" && *(at - 1) != "--log-level") break;
        words.insert(at == words.end() ? at : at + 1, "--skip-existing");
    }
    std::string command;
    for (const std::string& w : words) command += (command.empty() ? "" : " ") + shell_word(w);
    return command;
}

}  // namespace kdray::cli
