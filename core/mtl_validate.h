// mtl_validate.h — kdray's pre-scan of an MTL material library, run before tinyobjloader parses it
// (the OBJ pre-scan's rules for the MTL file): tinyobjloader reads `Kd nan` as 0, accepts a
// negative colour, a negative index of refraction, or a `d` outside [0, 1], all of which
// would shade wrongly without a word. The pre-scan rejects each with "NAME:LINE: problem".
#pragma once

#include <string>
#include <string_view>

namespace kdray {

/// Checks the statements kdray reads: colours (Ka, Kd, Ks, Ke, Tf and its alias Kt) are one or three finite
/// numbers >= 0, Ns and Ni finite numbers >= 0 (BART writes Ni 0 for opaque materials; the loader
/// warns about a material that transmits with Ni 0), d and Tr finite numbers in
/// [0, 1], illum an integer from 0 to 10; every numeric statement belongs to a `newmtl`. Other
/// statements (texture maps and extensions) are left to the loader.
void validate_mtl(std::string_view text, const std::string& name);

}  // namespace kdray
