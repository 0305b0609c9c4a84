// obj_validate.cpp — the OBJ pre-scan: one pass over the file's bytes, a hand-written line
// scanner and std::from_chars, so that it costs a small fraction of tinyobjloader's own parse.
#include "core/scene/obj_validate.h"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>

#include "core/error.h"
#include "core/scene/obj_number.h"

namespace kdray {
namespace {

/// The most triangulation work a file may ask for: the sum of n^2 over its faces of n > 4
/// vertices. 2^28 is one face of 16384 vertices: tinyobjloader's ear clipping (g++ -O2, a 2-core
/// EPYC, busy) took 1.4 s on a convex 16384-gon, 2.2 s on a concave zigzag and 1.6 s on a
/// spiral strip of as many vertices; 125-140 ms at 4096.
constexpr double kPolygonWorkBudget = double(1 << 28);

constexpr bool is_blank(char c) {
    return c == ' ' || c == '\t';
}

/// A token as it may appear in a message: at most 40 bytes, anything unprintable as \xNN, so
/// that a binary file cannot put raw bytes on the user's terminal.
std::string printable(std::string_view token) {
    std::string out;
    for (std::size_t i = 0; i < token.size() && i < 40; ++i) {
        const auto c = static_cast<unsigned char>(token[i]);
        if (c >= 0x20 && c < 0x7f) {
            out += static_cast<char>(c);
        } else {
            char buf[8];
            std::snprintf(buf, sizeof buf, "\\x%02x", c);
            out += buf;
        }
    }
    if (token.size() > 40) out += "...";
    return out;
}

/// The face attributes an index may refer to, with the words the messages use.
enum class Attribute { vertex, texcoord, normal };

const char* singular(Attribute a) {
    switch (a) {
        case Attribute::vertex:
            return "vertex";
        case Attribute::texcoord:
            return "texture coordinate";
        case Attribute::normal:
            return "normal";
    }
    return "";
}

const char* plural(Attribute a) {
    switch (a) {
        case Attribute::vertex:
            return "vertices";
        case Attribute::texcoord:
            return "texture coordinates";
        case Attribute::normal:
            return "normals";
    }
    return "";
}

/// Statements of the OBJ specification (and tinyobjloader's `vw`/`t` extensions) that kdray
/// accepts without looking inside; anything else is not an OBJ file kdray understands.
bool is_known_statement(std::string_view k) {
    static constexpr std::string_view known[] = {
        "usemtl",    "g",     "o",        "s",        "mtllib", "l",      "p",      "vp",
        "vw",        "t",     "cstype",   "deg",      "bmat",   "step",   "curv",   "curv2",
        "surf",      "parm",  "trim",     "hole",     "scrv",   "sp",     "end",    "con",
        "mg",        "bevel", "c_interp", "d_interp", "lod",    "usemap", "maplib", "shadow_obj",
        "trace_obj", "ctech", "stech",    "call",     "csh"};
    for (std::string_view s : known)
        if (k == s) return true;
    return false;
}

/// A positive index that points past the attributes defined so far; it is valid only if the
/// rest of the file defines enough of them, which is known at the end.
struct ForwardReference {
    std::size_t line;
    long long index;
    Attribute attribute;
};

class ObjScanner {
  public:
    ObjScanner(std::string_view text, const std::string& name) : text_(text), name_(name) {}

    ObjPrescan run() {
        const char* p = text_.data();
        const char* const end = p + text_.size();
        // Skip a UTF-8 byte order mark; tinyobjloader would not see a statement behind it, so
        // only a comment or a blank line may follow it.
        bool after_bom = false;
        if (text_.size() >= 3 && text_.substr(0, 3) == "\xEF\xBB\xBF") {
            p += 3;
            after_bom = true;
        }
        while (p < end) {
            ++line_;
            // Find the line's end ("\n", "\r\n" or a lone "\r", as tinyobjloader splits lines),
            // rejecting control bytes on the way: they mean a binary or corrupt file.
            const char* e = p;
            for (;;) {
                while (e < end && static_cast<unsigned char>(*e) >= 0x20) ++e;
                if (e == end || *e == '\n' || *e == '\r') break;
                if (*e != '\t')
                    fail("unexpected byte " + printable(std::string_view(e, 1)) +
                         ": this is not a text OBJ file");
                ++e;
            }
            if (after_bom) {
                check_after_bom(p, e);
                after_bom = false;
            }
            scan_line(p, e);
            if (e < end && *e == '\r' && e + 1 < end && e[1] == '\n') ++e;
            p = e + 1;
        }
        check_forward_references();
        return result_;
    }

  private:
    [[noreturn]] void fail(const std::string& what) const {
        throw Error(name_ + ":" + std::to_string(line_) + ": " + what);
    }

    void check_after_bom(const char* p, const char* e) {
        while (p < e && is_blank(*p)) ++p;
        if (p < e && *p != '#')
            fail(
                "a UTF-8 byte order mark precedes a statement, which tinyobjloader would skip; "
                "remove the mark");
    }

    /// The next blank-separated token of [p, e), advancing p; empty at the line's end or at a
    /// comment.
    static std::string_view next_token(const char*& p, const char* e) {
        while (p < e && is_blank(*p)) ++p;
        if (p == e || *p == '#') return {};
        const char* start = p;
        while (p < e && !is_blank(*p)) ++p;
        return {start, static_cast<std::size_t>(p - start)};
    }

    void scan_line(const char* p, const char* e) {
        std::string_view keyword = next_token(p, e);
        if (keyword.empty()) return;
        // tinyobjloader counts `vn`/`vt` only when a blank follows the keyword; so does this.
        const bool blank_follows = p < e;
        if (keyword == "v") return scan_vertex(p, e);
        if (keyword == "f") return scan_face(p, e);
        if (keyword == "vt") {
            if (blank_follows) scan_texcoord(p, e);
            return;
        }
        if (keyword == "vn") {
            if (blank_follows) scan_normal(p, e);
            return;
        }
        if (keyword == "mtllib") return scan_mtllib(p, e);
        if (keyword == "vw") return scan_vertex_weights(p, e);
        if (!is_known_statement(keyword)) fail("unknown statement '" + printable(keyword) + "'");
    }

    void scan_vertex(const char* p, const char* e) {
        int count = 0;
        double xyz[3];
        for (std::string_view token; !(token = next_token(p, e)).empty(); ++count) {
            double value = 0;
            check_number(token, "vertex coordinate", &value);
            if (count < 3) xyz[count] = value;
        }
        if (count != 3 && count != 4 && count != 6)
            fail("vertex has " + std::to_string(count) +
                 " numbers; expected 'x y z', 'x y z w' or 'x y z r g b'");
        result_.positions.insert(result_.positions.end(), xyz, xyz + 3);
        ++result_.vertices;
    }

    /// A shading normal: three finite numbers (kdray shades with them; tinyobjloader would read a
    /// missing one as 0 and a NaN as NaN).
    void scan_normal(const char* p, const char* e) {
        int count = 0;
        for (std::string_view token; !(token = next_token(p, e)).empty(); ++count)
            check_number(token, "normal component");
        if (count != 3)
            fail("normal has " + std::to_string(count) + " numbers; expected 'vn x y z'");
        ++result_.normals;
    }

    /// A texture coordinate: `vt u [v [w]]`, each finite as a float. tinyobjloader would read
    /// `1e39` as inf and `0e725` as NaN, and a texture lookup turns a non-finite u into an index
    /// far outside its texture.
    void scan_texcoord(const char* p, const char* e) {
        int count = 0;
        for (std::string_view token; !(token = next_token(p, e)).empty(); ++count)
            check_number(token, "texture coordinate");
        if (count < 1 || count > 3)
            fail("texture coordinate has " + std::to_string(count) +
                 " numbers; expected 'vt u', 'vt u v' or 'vt u v w'");
        ++result_.texcoords;
    }

    /// `vw vertex joint weight joint weight ...`, tinyobjloader's skinning extension, which kdray
    /// ignores but tinyobjloader parses: it converts each joint id to int, so a joint of 1e127
    /// (inf as its float) is undefined behaviour there (UBSan stopped fuzz_obj on it). Joints must
    /// be whole numbers from 0 to 2^31 - 1 and weights finite; the vertex is an int.
    void scan_vertex_weights(const char* p, const char* e) {
        const std::string_view vertex = next_token(p, e);
        int vertex_id = 0;
        const char* const last = vertex.data() + vertex.size();
        auto [ptr, ec] = std::from_chars(vertex.data(), last, vertex_id);
        if (vertex.empty() || ec != std::errc() || ptr != last)
            fail("vertex weight line's vertex '" + printable(vertex) +
                 "' is not an integer of 32 bits");
        int count = 0;
        for (std::string_view token; !(token = next_token(p, e)).empty(); ++count) {
            double value = 0;
            check_number(token, count % 2 == 0 ? "joint id" : "joint weight", &value);
            // 2147483520 is the largest float below 2^31: tinyobjloader holds the id as a float.
            if (count % 2 == 0 && (value < 0 || value > 2147483520.0 || value != std::floor(value)))
                fail("joint id '" + printable(token) + "' is not a whole number from 0 to 2^31");
        }
        if (count % 2 != 0) fail("vertex weight line has a joint without a weight");
    }

    /// A number of a `v`, `vt` or `vn` line (`what` names it in the error): finite as a 32-bit
    /// float, as tinyobjloader reads it; its value in `value` when given.
    void check_number(std::string_view token, const char* what, double* value = nullptr) const {
        if (const char* problem = obj_number_problem(token, value))
            fail(std::string(what) + " '" + printable(token) + "' " + problem);
    }

    void scan_face(const char* p, const char* e) {
        std::size_t count = 0;
        for (std::string_view token; !(token = next_token(p, e)).empty(); ++count)
            check_face_vertex(token);
        if (count < 3)
            fail("face has " + std::to_string(count) + " vertices; a face needs at least 3");
        ++result_.faces;
        result_.triangles += count - 2;
        // tinyobjloader clips the ears of a polygon of more than 4 vertices in time that grows
        // with the square of its size (or worse): one face of 100,000 vertices took 20 s. The
        // square of every such face is budgeted, so that no file triangulates for long.
        if (count > 4) {
            polygon_work_ += double(count) * double(count);
            if (polygon_work_ > kPolygonWorkBudget)
                fail("face of " + std::to_string(count) +
                     " vertices: the squares of the vertex counts of this file's polygons add up "
                     "past 2^28 here, the most kdray triangulates (one face of 16384 vertices, "
                     "about 2 s); split the large faces into triangles or smaller polygons");
        }
    }

    /// One face vertex: "v", "v/vt", "v//vn" or "v/vt/vn".
    void check_face_vertex(std::string_view token) {
        std::string_view parts[3];
        std::size_t n = 0, start = 0;
        for (std::size_t i = 0; i <= token.size(); ++i) {
            if (i == token.size() || token[i] == '/') {
                if (n == 3) fail("face vertex '" + printable(token) + "' has more than 3 parts");
                parts[n++] = token.substr(start, i - start);
                start = i + 1;
            }
        }
        const bool malformed =
            parts[0].empty() || (n == 2 && parts[1].empty()) || (n == 3 && parts[2].empty());
        if (malformed)
            fail("face vertex '" + printable(token) +
                 "' is malformed; expected 'v', 'v/vt', 'v//vn' or 'v/vt/vn'");
        check_index(parts[0], token, Attribute::vertex, result_.vertices);
        if (n >= 2 && !parts[1].empty())
            check_index(parts[1], token, Attribute::texcoord, result_.texcoords);
        if (n == 3) check_index(parts[2], token, Attribute::normal, result_.normals);
    }

    void check_index(std::string_view text, std::string_view token, Attribute attribute,
                     std::size_t defined) {
        std::string_view digits = text;
        if (digits.size() > 1 && digits[0] == '+') digits.remove_prefix(1);
        long long index = 0;
        const char* const last = digits.data() + digits.size();
        auto [ptr, ec] = std::from_chars(digits.data(), last, index);
        if (ec != std::errc() || ptr != last)
            fail("face " + std::string(singular(attribute)) + " index '" + printable(text) +
                 "' in '" + printable(token) + "' is not an integer");
        // Messages are built only on failure: this runs for every index of every face.
        auto what = [&] {
            return "face " + std::string(singular(attribute)) + " index " + std::to_string(index);
        };
        if (index == 0) fail(what() + " is invalid: OBJ indices start at 1");
        // The magnitude in unsigned arithmetic: -index overflows for the most negative index.
        const unsigned long long magnitude = 0ULL - static_cast<unsigned long long>(index);
        if (index < 0 && magnitude > defined)
            fail(what() + " reaches before the first " + singular(attribute) + ": only " +
                 std::to_string(defined) + " " + plural(attribute) +
                 " are defined before this line");
        if (index > 0 && static_cast<unsigned long long>(index) > defined)
            forward_.push_back({line_, index, attribute});
    }

    void check_forward_references() {
        for (const ForwardReference& f : forward_) {
            const std::size_t total = f.attribute == Attribute::vertex     ? result_.vertices
                                      : f.attribute == Attribute::texcoord ? result_.texcoords
                                                                           : result_.normals;
            if (static_cast<unsigned long long>(f.index) > total) {
                line_ = f.line;
                fail("face " + std::string(singular(f.attribute)) + " index " +
                     std::to_string(f.index) + " is out of range: the file has " +
                     std::to_string(total) + " " + plural(f.attribute));
            }
        }
    }

    /// `mtllib a.mtl b.mtl`: names separated by spaces, a backslash escaping a space, as
    /// tinyobjloader splits them.
    void scan_mtllib(const char* p, const char* e) {
        while (p < e && is_blank(*p)) ++p;
        std::string current;
        auto flush = [&] {
            if (!current.empty()) result_.material_libraries.push_back({current, line_});
            current.clear();
        };
        for (; p < e; ++p) {
            if (*p == '\\' && p + 1 < e && p[1] == ' ') {
                current += ' ';
                ++p;
            } else if (*p == ' ') {
                flush();
            } else {
                current += *p;
            }
        }
        flush();
    }

    std::string_view text_;
    const std::string& name_;
    std::size_t line_ = 0;
    ObjPrescan result_;
    std::vector<ForwardReference> forward_;
    double polygon_work_ = 0;  // the squares of the vertex counts of the faces over 4
};

}  // namespace

ObjPrescan validate_obj(std::string_view text, const std::string& name) {
    return ObjScanner(text, name).run();
}

}  // namespace kdray
