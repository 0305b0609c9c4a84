/* primitives.cl — the data-parallel building blocks of the kd-tree build (Zhou et al. 2008, §3
 * relies on scan, compaction and segmented reduction throughout): exclusive scan of uint, stream
 * compaction by flags, segmented min/max reduction of boxes, and a fill.
 *
 * No kernel here uses barriers or local memory: each work-item owns a contiguous chunk and works
 * through it sequentially, and the host chains launches (chunk sums, scan of the sums, add
 * offsets). That is portable to any OpenCL 1.2 device, and it sidesteps PoCL's history of
 * miscompiling barriers inside loops; on a 2-core CPU it is also what runs fastest, since a
 * work-group's items run one after another anyway.
 *
 * Boxes are KDRAY_BOX_FLOATS (6) floats: lo.xyz, hi.xyz. An empty box is lo = +inf, hi = -inf. */
#include "core/device/kd_shared.h"
#include "core/device/kd_build_shared.h"

/* Scan, step 1: work-item i scans elements [i*chunk, min(n, (i+1)*chunk)) sequentially into out
 * (exclusive, starting from 0) and writes the chunk's total to sums[i]. out may alias in. */
__kernel void kd_scan_chunks(__global const uint* in, __global uint* out, uint n, uint chunk,
                             uint chunks, __global uint* sums) {
    const uint i = get_global_id(0);
    if (i >= chunks) return;
    const uint begin = i * chunk;
    const uint end = min(n, begin + chunk);
    uint sum = 0;
    for (uint k = begin; k < end; ++k) {
        const uint v = in[k];
        out[k] = sum;
        sum += v;
    }
    sums[i] = sum;
}

/* Scan, base case: one work-item scans all n elements and writes the total to out[n]. */
__kernel void kd_scan_single(__global const uint* in, __global uint* out, uint n) {
    if (get_global_id(0) != 0) return;
    uint sum = 0;
    for (uint k = 0; k < n; ++k) {
        const uint v = in[k];
        out[k] = sum;
        sum += v;
    }
    out[n] = sum;
}

/* Scan, step 3: adds each chunk's offset (the scanned chunk sums) to its elements, and copies the
 * grand total, offsets[chunks], to out[n]. */
__kernel void kd_add_chunk_offsets(__global uint* out, uint n, uint chunk, uint chunks,
                                   __global const uint* offsets) {
    const uint k = get_global_id(0);
    if (k < n) out[k] += offsets[k / chunk];
    if (k == 0) out[n] = offsets[chunks];
}

/* Scan, step 3 by chunk: work-item i adds offsets[i] to chunk i's elements, one sequential
 * stream per work-item (for CPU devices, where one work-item per element is the cost). */
__kernel void kd_add_chunk_offsets_by_chunk(__global uint* out, uint n, uint chunk, uint chunks,
                                            __global const uint* offsets) {
    const uint i = get_global_id(0);
    if (i >= chunks) return;
    const uint begin = i * chunk, end = min(n, begin + chunk), offset = offsets[i];
    for (uint k = begin; k < end; ++k) out[k] += offset;
    if (i == 0) out[n] = offsets[chunks];
}

/* out[k] = in[k] for k < n: a device copy that Oclgrind tracks (see ClPrimitives::copy). */
__kernel void kd_copy_uint(__global const uint* in, __global uint* out, uint n) {
    const uint k = get_global_id(0);
    if (k < n) out[k] = in[k];
}

/* out[k] = value for k < n. */
__kernel void kd_fill_uint(__global uint* out, uint value, uint n) {
    const uint k = get_global_id(0);
    if (k < n) out[k] = value;
}

/* Compaction: element k with flags[k] != 0 goes to out[positions[k]], positions being the
 * exclusive scan of the flags (0/1). */
__kernel void kd_compact_by_flags(__global const uint* values, __global const uint* flags,
                                  __global const uint* positions, uint n, __global uint* out) {
    const uint k = get_global_id(0);
    if (k < n && flags[k]) out[positions[k]] = values[k];
}

/* out = the union of boxes[first .. end) (lo.xyz hi.xyz each); an empty range gives
 * lo = +inf, hi = -inf. Both steps of the segmented reduction below are this loop. */
KDRAY_INLINE void kd_union_boxes(__global const float* boxes, uint first, uint end,
                                 __global float* out) {
    float3 bmin = (float3)(INFINITY), bmax = (float3)(-INFINITY);
    for (uint k = first; k < end; ++k) {
        __global const float* b = boxes + (size_t)k * KDRAY_BOX_FLOATS;
        bmin = fmin(bmin, (float3)(b[0], b[1], b[2]));
        bmax = fmax(bmax, (float3)(b[3], b[4], b[5]));
    }
    out[0] = bmin.x, out[1] = bmin.y, out[2] = bmin.z;
    out[3] = bmax.x, out[4] = bmax.y, out[5] = bmax.z;
}

/* Segmented reduction, chunks of at most KDRAY_REDUCE_CHUNK (core/device/kd_build_shared.h)
 * elements: segment s covers boxes [seg_start[s], seg_start[s] + seg_count[s]) and owns chunks
 * [chunk_start[s], chunk_start[s + 1]), ceil(count / chunk) of them. Work-item c finds its
 * segment by binary search and writes the union of its chunk's boxes to chunk_boxes[c]. */
__kernel void kd_reduce_box_chunks(__global const float* boxes, __global const uint* seg_start,
                                   __global const uint* seg_count,
                                   __global const uint* chunk_start, uint segments,
                                   uint total_chunks, __global float* chunk_boxes) {
    const uint c = get_global_id(0);
    if (c >= total_chunks) return;
    /* Last segment whose first chunk is <= c (segments without chunks are skipped over). */
    uint lo = 0, hi = segments;
    while (hi - lo > 1) {
        const uint mid = (lo + hi) / 2;
        if (chunk_start[mid] <= c) lo = mid;
        else hi = mid;
    }
    const uint s = lo;
    const uint local_chunk = c - chunk_start[s];
    const uint begin = seg_start[s] + local_chunk * KDRAY_REDUCE_CHUNK;
    const uint end = min(seg_start[s] + seg_count[s], begin + KDRAY_REDUCE_CHUNK);
    kd_union_boxes(boxes, begin, end, chunk_boxes + (size_t)c * KDRAY_BOX_FLOATS);
}

/* Segmented reduction, step 2: segment s's box is the union of its chunks' boxes. */
__kernel void kd_reduce_box_segments(__global const float* chunk_boxes,
                                     __global const uint* chunk_start, uint segments,
                                     __global float* seg_boxes) {
    const uint s = get_global_id(0);
    if (s >= segments) return;
    kd_union_boxes(chunk_boxes, chunk_start[s], chunk_start[s + 1],
                   seg_boxes + (size_t)s * KDRAY_BOX_FLOATS);
}

/* Chunks per segment, for the scan that gives chunk_start: ceil(count / KDRAY_REDUCE_CHUNK). */
__kernel void kd_count_box_chunks(__global const uint* seg_count, uint segments,
                                  __global uint* chunks) {
    const uint s = get_global_id(0);
    if (s < segments) chunks[s] = (seg_count[s] + KDRAY_REDUCE_CHUNK - 1) / KDRAY_REDUCE_CHUNK;
}
