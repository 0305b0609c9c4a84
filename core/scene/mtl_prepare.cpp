#include "core/scene/mtl_prepare.h"

#include <cmath>
#include <vector>

#include "core/error.h"
#include "core/scene/obj_number.h"

namespace kdray {
namespace {

bool is_blank(char c) {
    return c == ' ' || c == '\t' || c == '\r';
}

std::vector<std::string_view> tokens(std::string_view line) {
    std::vector<std::string_view> out;
    std::size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && is_blank(line[i])) ++i;
        const std::size_t start = i;
        while (i < line.size() && !is_blank(line[i])) ++i;
        if (i > start) out.push_back(line.substr(start, i - start));
    }
    return out;
}

/// What one numeric statement may hold.
struct NumericRule {
    std::string_view keyword;
    std::size_t min_values, max_values;
    double lo, hi;  // both allowed: Ni 0 too (mtl_prepare.h)
    bool integer;
    const char* range;  // for messages
};

constexpr double kInf = INFINITY;
constexpr NumericRule kRules[] = {
    {"Ka", 1, 3, 0, kInf, false, ">= 0"},    {"Kd", 1, 3, 0, kInf, false, ">= 0"},
    {"Ks", 1, 3, 0, kInf, false, ">= 0"},    {"Ke", 1, 3, 0, kInf, false, ">= 0"},
    {"Tf", 1, 3, 0, kInf, false, ">= 0"},    {"Kt", 1, 3, 0, kInf, false, ">= 0"},
    {"Ns", 1, 1, 0, kInf, false, ">= 0"},    {"Ni", 1, 1, 0, kInf, false, ">= 0"},
    {"d", 1, 1, 0, 1, false, "in [0, 1]"},   {"Tr", 1, 1, 0, 1, false, "in [0, 1]"},
    {"illum", 1, 1, 0, 10, true, "0 to 10"},
};

}  // namespace

std::string prepare_mtl(std::string_view text, const std::string& name) {
    std::string out;
    out.reserve(text.size() + text.size() / 4);
    std::size_t line_no = 0;
    bool in_material = false;
    std::size_t pos = 0;
    while (pos < text.size()) {
        // Lines end in \n, \r\n or a lone \r, as tinyobjloader reads them.
        std::size_t end = text.find_first_of("\r\n", pos);
        if (end == std::string_view::npos) end = text.size();
        const std::string_view line = text.substr(pos, end - pos);
        pos = end + (end + 1 < text.size() && text[end] == '\r' && text[end + 1] == '\n' ? 2 : 1);
        ++line_no;
        auto fail = [&](const std::string& what) {
            throw Error(name + ":" + std::to_string(line_no) + ": " + what);
        };
        // A '#' starts a comment, also after a statement (McGuire's `Ka 0.63 0.065 0.05 # Red`).
        const std::vector<std::string_view> t = tokens(line.substr(0, line.find('#')));
        const NumericRule* rule = nullptr;
        for (const NumericRule& r : kRules)
            if (!t.empty() && t[0] == r.keyword) rule = &r;
        if (!rule) {
            if (!t.empty() && t[0] == "newmtl") {
                if (t.size() < 2) fail("newmtl without a material name");
                in_material = true;
            }
            out.append(line).push_back('\n');
            continue;
        }
        // `Tf xyz r g b` and `Tf spectral file`: colour spaces kdray does not read.
        if ((rule->keyword == "Tf" || rule->keyword == "Kt") && t.size() > 1 &&
            (t[1] == "xyz" || t[1] == "spectral"))
            fail(std::string(rule->keyword) + " " + std::string(t[1]) +
                 " is not supported; give it as r g b");
        if (!in_material) fail(std::string(rule->keyword) + " before any newmtl");
        const std::size_t n = t.size() - 1;
        if (n < rule->min_values || n > rule->max_values || (rule->max_values == 3 && n == 2))
            fail(std::string(rule->keyword) + " expects " +
                 (rule->min_values == rule->max_values ? std::string("one number")
                                                       : std::string("one or three numbers")) +
                 ", not " + std::to_string(n));
        for (std::size_t i = 1; i < t.size(); ++i) {
            double v = 0;
            const std::string value(t[i].substr(0, 40));
            if (const char* problem = obj_number_problem(t[i], &v))
                fail(std::string(rule->keyword) + " value '" + value + "' " + problem);
            const bool in_range =
                v >= rule->lo && v <= rule->hi && (!rule->integer || v == std::floor(v));
            if (!in_range)
                fail(std::string(rule->keyword) + " value '" + value + "' must be " +
                     (rule->integer ? "an integer " : "a finite number ") + rule->range);
        }
        // tinyobjloader reads the first three tokens as r g b whatever follows (a '#' glued
        // to a number included) and defaults missing ones to 0: it is given the values
        // alone, a colour of one value written out as the grey it means (r r r).
        out.append(t[0]);
        const std::size_t copies = rule->max_values == 3 && n == 1 ? 3 : 1;
        for (std::size_t i = 1; i < t.size(); ++i)
            for (std::size_t c = 0; c < copies; ++c) out.append(" ").append(t[i]);
        out.push_back('\n');
    }
    return out;
}

}  // namespace kdray
