/* layout.cl — reports the device compiler's sizeof of every struct in core/device/kd_shared.h and
 * core/device/kd_build_shared.h, so that a test can compare it with the host's: the headers are
 * only shared safely while both compilers lay the structs out alike. out[0] = number of entries,
 * then one sizeof each, in the order KdNode, KdRay, KdHit, KdMaterial, KdLight, KdView,
 * KdRayCounts, KdBuildBox, KdBuildNode, KdSmallNode, KdLargeNode, KdLargeSplit, KdLargeCuts,
 * KdSmallRoot, KdLargeSplitArgs, KdLargeLevelArgs, KdSmallBatchArgs, KdEmitter, KdTexture,
 * KdSmallLevelNode, KdSceneLayout, KdRenderLaunch, KdTraceCost, KdDepthFirstArgs, KdLargeRegion, KdDepthFirstTask. */
#include "core/device/kd_build_shared.h"
#include "core/device/kd_shared.h"

__kernel void kd_report_layout(__global uint* out) {
    if (get_global_id(0) != 0) return;
    out[0] = 26;
    out[1] = sizeof(KdNode);
    out[2] = sizeof(KdRay);
    out[3] = sizeof(KdHit);
    out[4] = sizeof(KdMaterial);
    out[5] = sizeof(KdLight);
    out[6] = sizeof(KdView);
    out[7] = sizeof(KdRayCounts);
    out[8] = sizeof(KdBuildBox);
    out[9] = sizeof(KdBuildNode);
    out[10] = sizeof(KdSmallNode);
    out[11] = sizeof(KdLargeNode);
    out[12] = sizeof(KdLargeSplit);
    out[13] = sizeof(KdLargeCuts);
    out[14] = sizeof(KdSmallRoot);
    out[15] = sizeof(KdLargeSplitArgs);
    out[16] = sizeof(KdLargeLevelArgs);
    out[17] = sizeof(KdSmallBatchArgs);
    out[18] = sizeof(KdEmitter);
    out[19] = sizeof(KdTexture);
    out[20] = sizeof(KdSmallLevelNode);
    out[21] = sizeof(KdSceneLayout);
    out[22] = sizeof(KdRenderLaunch);
    out[23] = sizeof(KdTraceCost);
    out[24] = sizeof(KdDepthFirstArgs);
    out[25] = sizeof(KdLargeRegion);
    out[26] = sizeof(KdDepthFirstTask);
}
