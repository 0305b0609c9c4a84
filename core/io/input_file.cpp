#include "core/io/input_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <limits>
#include <unordered_set>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/error.h"
#include "core/io/frame_memory.h"

namespace kdray {
namespace {

std::filesystem::file_type type_of(mode_t mode) {
    using std::filesystem::file_type;
    if (S_ISDIR(mode)) return file_type::directory;
    if (S_ISFIFO(mode)) return file_type::fifo;
    if (S_ISCHR(mode)) return file_type::character;
    if (S_ISBLK(mode)) return file_type::block;
    if (S_ISSOCK(mode)) return file_type::socket;
    return file_type::unknown;
}

/// Closes the descriptor on every path out of read_input_file.
struct Descriptor {
    int fd;
    ~Descriptor() {
        if (fd >= 0) ::close(fd);
    }
};

}  // namespace

const char* file_type_name(std::filesystem::file_type type) {
    switch (type) {
        case std::filesystem::file_type::directory:
            return "a directory";
        case std::filesystem::file_type::symlink:
            return "a symbolic link";
        case std::filesystem::file_type::block:
            return "a block device";
        case std::filesystem::file_type::character:
            return "a character device";
        case std::filesystem::file_type::fifo:
            return "a FIFO";
        case std::filesystem::file_type::socket:
            return "a socket";
        default:
            return "not a regular file";
    }
}

std::uint64_t input_size_limit() {
    const std::uint64_t physical = physical_memory_bytes();
    return physical > 0 ? physical / 4 : std::uint64_t(4) << 30;
}

std::string read_input_file(const std::filesystem::path& path, std::string_view what,
                            std::uint64_t max_bytes) {
    const std::string name = path.string();
    // O_NONBLOCK: opening a FIFO for reading would otherwise wait for a writer, for ever.
    Descriptor file{::open(name.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC)};
    if (file.fd < 0) throw Error(name + ": cannot open: " + std::strerror(errno));
    struct stat info {};
    if (::fstat(file.fd, &info) != 0) throw Error(name + ": cannot open: " + std::strerror(errno));
    // A directory opens on Linux; it is said as open(2) says it for writing.
    if (S_ISDIR(info.st_mode)) throw Error(name + ": cannot open: " + std::strerror(EISDIR));
    if (!S_ISREG(info.st_mode))
        throw Error(name + ": not a regular file (" + file_type_name(type_of(info.st_mode)) + ")");
    const auto size = static_cast<std::uint64_t>(info.st_size);
    if (size > max_bytes)
        throw Error(name + ": " + std::to_string(size) + " bytes, more than the " +
                    std::to_string(max_bytes) + " bytes kdray reads of one " + std::string(what) +
                    " here");
    std::string text(static_cast<std::size_t>(size), '\0');
    std::size_t done = 0;
    // A file that grows while it is read is read up to the size it had.
    while (done < text.size()) {
        const ssize_t n = ::read(file.fd, text.data() + done, text.size() - done);
        if (n < 0 && errno == EINTR) continue;
        if (n < 0) throw Error(name + ": cannot read: " + std::strerror(errno));
        if (n == 0) break;  // it shrank
        done += std::size_t(n);
    }
    text.resize(done);
    return text;
}

void check_image_size(const std::string& name, std::int64_t width, std::int64_t height,
                      std::int64_t channels, std::uint64_t file_bytes) {
    const std::string size = std::to_string(width) + " x " + std::to_string(height) + " pixels, " +
                             std::to_string(channels) + " channels";
    if (width <= 0 || height <= 0 || channels <= 0)
        throw Error(name + ": an empty image (" + size + ")");
    // Bounding each factor first keeps the products within 64 bits.
    const bool huge =
        std::uint64_t(width) > kMaxImagePixels || std::uint64_t(height) > kMaxImagePixels;
    const std::uint64_t pixels = huge ? 0 : std::uint64_t(width) * std::uint64_t(height);
    if (huge || pixels > kMaxImagePixels)
        throw Error(name + ": an image of " + size + ", more than the " +
                    std::to_string(kMaxImagePixels) + " pixels kdray decodes of one image");
    if (pixels > kPlausibleImagePixels && pixels / kMaxPixelsPerFileByte >= file_bytes)
        throw Error(name + ": an image of " + size + " in a file of " + std::to_string(file_bytes) +
                    " bytes, more than the " + std::to_string(kMaxPixelsPerFileByte) +
                    " pixels a byte any image format packs; the file is damaged");
    const std::uint64_t bytes = std::uint64_t(channels) > kMaxImagePixels
                                    ? std::numeric_limits<std::uint64_t>::max()
                                    : pixels * std::uint64_t(channels) * 4;
    if (const std::uint64_t limit = input_size_limit(); bytes > limit)
        throw Error(name + ": an image of " + size + " takes " + std::to_string(bytes >> 20) +
                    " MiB decoded, more than the " + std::to_string(limit >> 20) +
                    " MiB kdray reads of one input here");
}

nlohmann::json parse_json(std::string_view text, const std::string& name) {
    using nlohmann::json;
    // Where the parse is: the open objects and arrays, outermost first, each object with the
    // keys it has had and its latest, each array with the number of elements it has had. A key
    // given twice is refused: nlohmann keeps the last one, Python's json too, other readers the
    // first, so the file means different things to kdray, its schema and the user's editor.
    struct Open {
        bool object = false;
        std::unordered_set<std::string> keys;
        std::string key;
        std::size_t elements = 0;
    };
    std::vector<Open> open;
    // Appended piece by piece: GCC 12 warns falsely (-Wstringop-overflow) on "." + std::string.
    auto where = [&](const std::string& last) {
        std::string path;
        for (std::size_t i = 0; i < open.size(); ++i) {
            const bool object = i + 1 == open.size() || open[i].object;
            if (object && !path.empty()) path += '.';
            if (i + 1 == open.size()) {
                path += last;
            } else if (object) {
                path += open[i].key;
            } else {
                path += '[';
                path += std::to_string(open[i].elements);
                path += ']';
            }
        }
        return path;
    };
    // An element of the innermost open array is complete.
    auto element_done = [&] {
        if (!open.empty() && !open.back().object) ++open.back().elements;
    };
    // The callback sees each array or object start with the depth of its parent: refusing there
    // stops the parse before the deep value exists.
    const json::parser_callback_t check = [&](int depth, json::parse_event_t event, json& parsed) {
        switch (event) {
            case json::parse_event_t::object_start:
            case json::parse_event_t::array_start:
                if (depth >= kMaxJsonDepth)
                    throw Error(name + ": JSON nested more than " + std::to_string(kMaxJsonDepth) +
                                " levels deep; kdray's files nest a few levels");
                open.push_back(Open{event == json::parse_event_t::object_start, {}, {}, 0});
                break;
            case json::parse_event_t::key: {
                Open& object = open.back();
                object.key = parsed.get<std::string>();
                if (!object.keys.insert(object.key).second)
                    throw Error(name + ": field '" + where(object.key) +
                                "' is given twice; each key of a JSON object may appear once");
                break;
            }
            case json::parse_event_t::object_end:
            case json::parse_event_t::array_end:
                open.pop_back();
                element_done();
                break;
            case json::parse_event_t::value:
                element_done();
                break;
        }
        return true;
    };
    try {
        return json::parse(text.begin(), text.end(), check);
    } catch (const json::parse_error& e) {
        // nlohmann's message begins with "[json.exception.parse_error.101] "; drop the tag.
        std::string what = e.what();
        if (const auto pos = what.find("] "); what.starts_with("[json") && pos != what.npos)
            what = what.substr(pos + 2);
        throw Error(name + ": invalid JSON at byte " + std::to_string(e.byte) + ": " + what);
    } catch (const json::exception& e) {
        // Not a syntax error but a value JSON cannot hold here, e.g. a number overflow.
        throw Error(name + ": invalid JSON: " + e.what());
    }
}

}  // namespace kdray
