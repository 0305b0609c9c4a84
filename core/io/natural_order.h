// natural_order.h — the order of an animation's frames: digit runs compare by value, so frame_2
// comes before frame_10. A frame's number is its position in this order (conventions.md).
#pragma once

#include <string>

namespace kdray {

bool natural_less(const std::string& a, const std::string& b);

}  // namespace kdray
