// obj_number.cpp — the OBJ and MTL pre-scans' number check: a fast path for the plain decimals
// that are nearly all of an OBJ file, std::from_chars for the rest, and tinyobjloader's limits.
#include "core/scene/obj_number.h"

#include <charconv>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <string>

namespace kdray {
namespace {

/// The fast path of the OBJ pre-scan's vertex check, which is most of its time: true when `token`
/// is a plain decimal number ([+-]digits[.digits][(e|E)[+-]digits]) whose magnitude is certainly
/// below 1e38, so below FLT_MAX. Anything else (nan, inf, huge values, garbage) is decided by
/// the exact path. Measured on bart-robots frame_000 (5 MB, 134k vertices, -O3): the pre-scan
/// takes 11.5 ms with this test in front of from_chars and 14 ms without it.
bool is_plain_float(std::string_view s) {
    std::size_t i = 0;
    const std::size_t n = s.size();
    if (n > kMaxObjNumberLength) return false;
    if (i < n && (s[i] == '+' || s[i] == '-')) ++i;
    // Decimal exponent of the leading significant digit, from the digits' positions.
    long magnitude = 0;
    bool seen_digit = false, seen_significant = false;
    for (; i < n && s[i] >= '0' && s[i] <= '9'; ++i) {
        seen_digit = true;
        if (seen_significant)
            ++magnitude;
        else if (s[i] != '0')
            seen_significant = true;
    }
    if (i < n && s[i] == '.') {
        ++i;
        for (; i < n && s[i] >= '0' && s[i] <= '9'; ++i) {
            seen_digit = true;
            if (!seen_significant) {
                --magnitude;
                if (s[i] != '0') seen_significant = true;
            }
        }
    }
    if (!seen_digit) return false;
    if (i < n && (s[i] == 'e' || s[i] == 'E')) {
        ++i;
        bool negative = false;
        if (i < n && (s[i] == '+' || s[i] == '-')) negative = s[i++] == '-';
        if (i == n) return false;
        long exponent = 0;
        for (; i < n && s[i] >= '0' && s[i] <= '9'; ++i)
            if (exponent < 100000) exponent = exponent * 10 + (s[i] - '0');
        // A saturated exponent is not the number's: 100k zeros after the point could then hide
        // an exponent of a million. Such a number takes the exact path.
        if (exponent >= 100000) return false;
        // tinyobjloader reads zero with a huge exponent as 0 · inf; the exact path rejects it.
        if (!negative && exponent > kMaxObjNumberExponent) return false;
        magnitude += negative ? -exponent : exponent;
    }
    return i == n && (!seen_significant || magnitude < 37);
}

/// The written decimal exponent of a number from_chars accepted, saturated at a million.
long written_exponent(std::string_view s) {
    const std::size_t e = s.find_first_of("eE");
    if (e == std::string_view::npos) return 0;
    std::size_t i = e + 1;
    bool negative = false;
    if (i < s.size() && (s[i] == '+' || s[i] == '-')) negative = s[i++] == '-';
    long exponent = 0;
    for (; i < s.size() && s[i] >= '0' && s[i] <= '9'; ++i)
        if (exponent < 1000000) exponent = exponent * 10 + (s[i] - '0');
    return negative ? -exponent : exponent;
}

}  // namespace

const char* obj_number_problem(std::string_view token, double* value) {
    static_assert(kMaxObjNumberLength == 64 && kMaxObjNumberExponent == 308,
                  "the messages below name both limits");
    if (!value && is_plain_float(token)) return nullptr;
    std::string_view digits = token;
    // tinyobjloader accepts a leading '+', which from_chars does not.
    if (digits.size() > 1 && digits[0] == '+' && digits[1] != '-' && digits[1] != '+')
        digits.remove_prefix(1);
    double parsed = 0;
    const char* const last = digits.data() + digits.size();
    auto [ptr, ec] = std::from_chars(digits.data(), last, parsed);
    if (ec == std::errc::invalid_argument || ptr != last) return "is not a number";
    if (ec == std::errc::result_out_of_range) {
        // from_chars reports underflow and overflow alike; strtod tells them apart (a value too
        // small for a double reads as zero, which is harmless).
        parsed = std::strtod(std::string(digits).c_str(), nullptr);
    }
    if (!std::isfinite(parsed)) return "is not a finite number";
    if (std::fabs(parsed) > std::numeric_limits<float>::max())
        return "is not a finite number as a 32-bit float";
    if (token.size() > kMaxObjNumberLength) return "is longer than the 64 characters kdray reads";
    if (written_exponent(digits) > kMaxObjNumberExponent)
        return "has an exponent above 308, which tinyobjloader reads as infinite";
    if (value) *value = parsed;
    return nullptr;
}

}  // namespace kdray
