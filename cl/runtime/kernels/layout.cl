/* layout.cl — reports the device compiler's sizeof of every struct in core/kd_shared.h, so that a
 * test can compare it with the host's: the one header is only shared safely while both compilers
 * lay the structs out alike. out[0] = number of entries, then one sizeof each, in the order
 * KdNode, KdRay, KdHit, KdMaterial, KdLight, KdView, KdRayCounts, KdBuildNode. */
#include "core/kd_shared.h"

__kernel void kd_report_layout(__global uint* out) {
    if (get_global_id(0) != 0) return;
    out[0] = 8;
    out[1] = sizeof(KdNode);
    out[2] = sizeof(KdRay);
    out[3] = sizeof(KdHit);
    out[4] = sizeof(KdMaterial);
    out[5] = sizeof(KdLight);
    out[6] = sizeof(KdView);
    out[7] = sizeof(KdRayCounts);
    out[8] = sizeof(KdBuildNode);
}
