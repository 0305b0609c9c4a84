// resume_command.h — the command that resumes an interrupted `kdray render`: the command line as
// it was typed, with --skip-existing, each word quoted for a POSIX shell so that it can be pasted
// back whatever the file names hold.
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace kdray::cli {

/// `word` as one shell word: bare when it holds only characters no shell treats specially, else
/// in single quotes ('it'\''s'); a word with control characters or bytes that are not UTF-8 is
/// written in bash's $'...' form with \xHH escapes, so that the result is one printable line.
std::string shell_word(std::string_view word);

/// `argv` (kdray's, from argv[0]) with --skip-existing after the `render` word unless it is there
/// already, each word through shell_word, separated by spaces.
std::string resume_command(const std::vector<std::string>& argv);

}  // namespace kdray::cli
