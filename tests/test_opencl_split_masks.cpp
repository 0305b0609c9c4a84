// test_opencl_split_masks.cpp — the small stage's split-candidate masks (build_small.cl) word for
// word against the rule they implement, computed here on the host: both shapes, a work-item per
// reference (GPUs, the per-level stage) and per KDRAY_MASK_GROUP references (CPUs, the per-root
// stage). The batches have roots of 1-7, 31-33, 63 and 64 references, groups of four that span
// several roots, and starts inside the reference list with ends off a group; the boxes lie on a
// coarse grid, so that many candidates share a plane and many boxes are flat on an axis.
#include <doctest/doctest.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <utility>
#include <vector>

#include "cl/builder/build_context.h"
#include "cl/runtime/launch.h"
#include "core/device/kd_build_shared.h"
#include "tests/test_opencl_fixture.h"

using namespace kdray;

namespace {

struct MaskBatch {
    std::vector<float> boxes;  // KDRAY_BOX_FLOATS per reference: lo xyz, hi xyz
    std::vector<cl_uint> ref_root;
    std::vector<KdSmallRoot> roots;
};

MaskBatch random_roots(std::uint32_t seed) {
    const cl_uint sizes[] = {1, 2, 3, 4, 5, 6, 7, 31, 32, 33, 63, 64};
    std::mt19937 rng(seed);
    MaskBatch b;
    const int roots = 20 + int(rng() % 30);
    for (int r = 0; r < roots; ++r) {
        KdSmallRoot root{};
        root.ref_start = cl_uint(b.ref_root.size());
        root.ref_count = rng() % 3 ? sizes[rng() % 12] : 1 + rng() % 64;
        b.roots.push_back(root);
        for (cl_uint i = 0; i < root.ref_count; ++i) {
            b.ref_root.push_back(cl_uint(r));
            float box[KDRAY_BOX_FLOATS];
            for (int a = 0; a < 3; ++a) {
                box[a] = 0.25f * float(rng() % 8);
                box[a + 3] = box[a] + 0.25f * float(rng() % 4);  // 0: flat on this axis
            }
            b.boxes.insert(b.boxes.end(), box, box + KDRAY_BOX_FLOATS);
        }
    }
    return b;
}

/// The masks of references [begin, begin + refs) by build_small.cl's rule: candidate lane
/// k = 2 axis + side of reference i lies at its box's lo (side 0) or hi (side 1) on that axis;
/// reference j of i's root goes below when lo_j < p or not hi_j > p, above when hi_j > p, except
/// in a hi lane of an axis on which i is flat, where j goes below when lo_j < p and above when
/// hi_j > p or lo_j >= p. Lanes 6 and 7 hold a plane at 0 against boxes at 0: every reference
/// below, none above.
std::vector<cl_ulong> masks_by_rule(const MaskBatch& b, cl_uint begin, cl_uint refs) {
    std::vector<cl_ulong> out(std::size_t(refs) * KDRAY_MASK_WORDS_PER_REF, 0);
    for (cl_uint i = begin; i < begin + refs; ++i) {
        const KdSmallRoot& root = b.roots[b.ref_root[i]];
        const float* box_i = &b.boxes[std::size_t(i) * KDRAY_BOX_FLOATS];
        for (int k = 0; k < 8; ++k) {
            const int axis = k / 2, side = k % 2;
            const bool padding = k >= 6;
            const float p = padding ? 0.0f : box_i[axis + 3 * side];
            const bool planar_above = !padding && side == 1 && box_i[axis] == box_i[axis + 3];
            cl_ulong below = 0, above = 0;
            for (cl_uint j = 0; j < root.ref_count; ++j) {
                const float* box_j = &b.boxes[std::size_t(root.ref_start + j) * KDRAY_BOX_FLOATS];
                const float lo = padding ? 0.0f : box_j[axis];
                const float hi = padding ? 0.0f : box_j[axis + 3];
                const bool is_above = hi > p || (planar_above && lo >= p);
                const bool is_below = lo < p || (!planar_above && !(hi > p));
                below |= cl_ulong(is_below) << j;
                above |= cl_ulong(is_above) << j;
            }
            cl_ulong* words = &out[std::size_t(i - begin) * KDRAY_MASK_WORDS_PER_REF];
            words[k] = below;
            words[8 + k] = above;
        }
    }
    return out;
}

template <class T>
cl::Buffer upload(ClDevice& device, const std::vector<T>& v) {
    cl::Buffer b = device.allocate(v.size() * sizeof(T), "test input");
    device.queue().enqueueWriteBuffer(b, CL_TRUE, 0, v.size() * sizeof(T), v.data());
    return b;
}

/// A word no mask of the rule's has in these batches (the test checks it): a kernel's buffer is
/// filled with it first, so that a word it leaves unwritten shows.
constexpr cl_ulong kUnwritten = 0xA5A5A5A5A5A5A5A5ull;

/// One kernel's masks of references [begin, begin + refs), over `items` work-items, into a buffer
/// of exactly their size.
std::vector<cl_ulong> masks_by_kernel(ClDevice& device, cl::Kernel& kernel, std::size_t items,
                                      cl_uint begin, cl_uint refs, const cl::Buffer& boxes,
                                      const cl::Buffer& ref_root, const cl::Buffer& roots) {
    std::vector<cl_ulong> out(std::size_t(refs) * KDRAY_MASK_WORDS_PER_REF, kUnwritten);
    cl::Buffer masks = upload(device, out);
    enqueue_kernel(device, kernel, items, begin, refs, boxes, ref_root, roots, masks);
    device.queue().enqueueReadBuffer(masks, CL_TRUE, 0, out.size() * sizeof(cl_ulong), out.data());
    return out;
}

}  // namespace

TEST_CASE("opencl split masks: both shapes write the rule's masks, word for word") {
    ClDevice& device = test::opencl_test_device();
    build_detail::BuilderKernels& kernels = build_detail::builder_kernels(device, 32);
    for (std::uint32_t seed : {3u, 17u, 2024u}) {
        const MaskBatch b = random_roots(seed);
        const cl::Buffer boxes = upload(device, b.boxes);
        const cl::Buffer ref_root = upload(device, b.ref_root);
        const cl::Buffer roots = upload(device, b.roots);
        const cl_uint total = cl_uint(b.ref_root.size());
        // The whole list; from the third root's start to the end; a window that starts and ends
        // inside roots (a batch never does, but a group must not care), one reference long too.
        const cl_uint third = b.roots[2].ref_start;
        const std::pair<cl_uint, cl_uint> batches[] = {
            {0, total}, {third, total - third}, {third + 1, total / 2 - 1}, {third + 5, 1}};
        for (const auto& [begin, refs] : batches) {
            CAPTURE(seed);
            CAPTURE(begin);
            CAPTURE(refs);
            const std::vector<cl_ulong> rule = masks_by_rule(b, begin, refs);
            CHECK(std::find(rule.begin(), rule.end(), kUnwritten) == rule.end());
            CHECK(masks_by_kernel(device, kernels.split_masks, refs, begin, refs, boxes, ref_root,
                                  roots) == rule);
            const std::size_t groups = (refs + KDRAY_MASK_GROUP - 1) / KDRAY_MASK_GROUP;
            CHECK(masks_by_kernel(device, kernels.split_masks_grouped, groups, begin, refs, boxes,
                                  ref_root, roots) == rule);
        }
    }
}
