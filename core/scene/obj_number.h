// obj_number.h — one number of an OBJ or MTL statement, judged as tinyobjloader will read it.
// The pre-scans (obj_validate, mtl_prepare) decide with std::from_chars, which is exact;
// tinyobjloader computes mantissa · 5^e · 2^e instead, which turns some exact finite values into
// inf or NaN: `0e725` reads as 0 · inf = NaN (fuzz_mtl found it), and 400 integer digits
// overflow the mantissa whatever the exponent. Both readers must agree that a number is finite.
#pragma once

#include <string_view>

namespace kdray {

/// The longest number kdray reads: more than any exporter writes (a float's shortest round trip
/// is at most 16 characters in scientific form), few enough that tinyobjloader's mantissa stays
/// finite.
inline constexpr std::size_t kMaxObjNumberLength = 64;

/// The largest written decimal exponent: tinyobjloader's 5^e overflows a double past 441, and a
/// finite float needs no exponent beyond 38 plus the digits before it.
inline constexpr long kMaxObjNumberExponent = 308;

/// nullptr when both from_chars and tinyobjloader read `token` as the same finite 32-bit float
/// (a leading '+' allowed, as tinyobjloader allows it; a value too small for a double is zero);
/// otherwise what is wrong, as a phrase to follow the quoted token ("is not a number"). When
/// `value` is given it receives the number.
const char* obj_number_problem(std::string_view token, double* value = nullptr);

}  // namespace kdray
