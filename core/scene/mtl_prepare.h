// mtl_prepare.h — kdray's pass over an MTL material library before tinyobjloader parses it (the
// OBJ pre-scan's rules for the MTL file). tinyobjloader reads `Kd nan` as 0, accepts a negative
// colour, a negative index of refraction, or a `d` outside [0, 1], all of which would shade
// wrongly without a word; the pass rejects each with "NAME:LINE: problem". It also hands
// tinyobjloader what the file means where tinyobjloader would read something else: `Kd 0.5` is
// grey to the MTL specification and (0.5, 0, 0) to tinyobjloader, and a comment glued to a number
// (`Ks 0.1# note`) is read by tinyobjloader as more numbers.
#pragma once

#include <string>
#include <string_view>

namespace kdray {

/// Checks the statements kdray reads: colours (Ka, Kd, Ks, Ke, Tf and its alias Kt) are one or
/// three finite numbers >= 0, Ns and Ni finite numbers >= 0 (BART writes Ni 0 for opaque
/// materials; the loader warns about a material that transmits with Ni 0), d and Tr finite
/// numbers in [0, 1], illum an integer from 0 to 10; every numeric statement belongs to a
/// `newmtl`. Returns the library for tinyobjloader, line for line: those statements with their
/// values alone (comments dropped, a one-value colour written as r r r), every other line as it
/// was (texture maps and extensions are left to the loader).
std::string prepare_mtl(std::string_view text, const std::string& name);

}  // namespace kdray
