/* build_large_groups.cl — the large-node stage's passes over the references in the shape of Zhou
 * et al. (2008, §4.1) on a GPU: a work-group per reduction chunk and a work-item per reference,
 * the chunk's boxes, bins and counts reduced in local memory (included by build_large.cl, whose
 * kernels of a work-item per chunk these mirror; cl/builder/large_level.cpp picks one set per
 * build, BuildParams::large_stage).
 *
 * Why both: a CPU runs a work-group's items one after another, so a work-item walking its chunk
 * in order is the cheapest shape there (no barriers, no local memory, one sequential stream). A
 * GPU runs them side by side: with a work-item per chunk the Kitchen's root level is 432
 * work-items, each walking 256 references 6 KB away from its neighbour's, well under 1% of a
 * large GPU; here it is 110k work-items whose neighbours read neighbouring records.
 *
 * Same results, bit for bit: a chunk holds the same references in the same order in both shapes;
 * boxes reduce by min and max and bins by integer sums (order-free), and a reference's rank among
 * its chunk's references that go to the same child is an exclusive scan of the chunk's flags, the
 * running count of the sequential loop. The tree is the same node for node (tests).
 *
 * Launch: the global size is chunks * G and the local size G, a power of two of at most
 * KDRAY_REDUCE_CHUNK (the device's limit for the kernel may be less); a group walks its chunk in
 * rounds of G references. Every loop with a barrier runs the same rounds in every work-item. */
#ifndef KDRAY_BUILD_LARGE_GROUPS_CL
#define KDRAY_BUILD_LARGE_GROUPS_CL

/* The node of chunk c (kd_find_segment over the level's chunk starts) and the chunk's references
 * [*begin, *end). */
KDRAY_INLINE uint kd_chunk_references(uint c, __global const uint* node_ref_start,
                                      __global const uint* node_ref_count,
                                      __global const uint* node_chunk, uint nodes, uint* begin,
                                      uint* end) {
    const uint i = kd_find_segment(node_chunk, nodes, c);
    const uint start = node_ref_start[i];
    *begin = start + (c - node_chunk[i]) * KDRAY_REDUCE_CHUNK;
    *end = min(start + node_ref_count[i], *begin + KDRAY_REDUCE_CHUNK);
    return i;
}

/* Exclusive scan of `value` over the work-group's items (Hillis & Steele, in local memory of at
 * least G words); *total gets the sum of all of them. Every work-item must call it. */
KDRAY_INLINE uint kd_group_exclusive_scan(uint value, __local uint* scratch, uint* total) {
    const uint l = get_local_id(0), g = get_local_size(0);
    scratch[l] = value;
    barrier(CLK_LOCAL_MEM_FENCE);
    for (uint offset = 1; offset < g; offset <<= 1) {
        const uint before = l >= offset ? scratch[l - offset] : 0u;
        barrier(CLK_LOCAL_MEM_FENCE);
        scratch[l] += before;
        barrier(CLK_LOCAL_MEM_FENCE);
    }
    const uint inclusive = scratch[l];
    *total = scratch[g - 1];
    barrier(CLK_LOCAL_MEM_FENCE); /* the next call overwrites scratch */
    return inclusive - value;
}

/* Node bounds, step 1 (primitives.cl's kd_reduce_box_chunks in this shape): the union of chunk
 * c's reference boxes, reduced in local memory by halving. */
__kernel void kd_reduce_box_chunk_groups(__global const float* ref_box,
                                         __global const uint* node_ref_start,
                                         __global const uint* node_ref_count,
                                         __global const uint* node_chunk, uint nodes,
                                         __global float* chunk_boxes) {
    __local float lo[3][KDRAY_REDUCE_CHUNK], hi[3][KDRAY_REDUCE_CHUNK];
    const uint c = get_group_id(0), l = get_local_id(0), g = get_local_size(0);
    uint begin, end;
    kd_chunk_references(c, node_ref_start, node_ref_count, node_chunk, nodes, &begin, &end);
    KdBox own;
    own.lo = (float3)(INFINITY);
    own.hi = (float3)(-INFINITY);
    for (uint r = begin + l; r < end; r += g) {
        const KdBox b = kd_load_box(ref_box, r);
        own.lo = fmin(own.lo, b.lo);
        own.hi = fmax(own.hi, b.hi);
    }
    lo[0][l] = own.lo.x, lo[1][l] = own.lo.y, lo[2][l] = own.lo.z;
    hi[0][l] = own.hi.x, hi[1][l] = own.hi.y, hi[2][l] = own.hi.z;
    barrier(CLK_LOCAL_MEM_FENCE);
    for (uint width = g / 2; width > 0; width /= 2) {
        if (l < width)
            for (uint k = 0; k < 3; ++k) {
                lo[k][l] = fmin(lo[k][l], lo[k][l + width]);
                hi[k][l] = fmax(hi[k][l], hi[k][l + width]);
            }
        barrier(CLK_LOCAL_MEM_FENCE);
    }
    if (l < 3) {
        chunk_boxes[(size_t)c * KDRAY_BOX_FLOATS + l] = lo[l][0];
        chunk_boxes[(size_t)c * KDRAY_BOX_FLOATS + 3 + l] = hi[l][0];
    }
}

#if KDRAY_LARGE_BINS > 0
/* kd_bin_large_chunks in this shape: chunk c's SAH bins, counted in local memory. */
__kernel void kd_bin_large_groups(__global const float* ref_box, __global const uint* node_start,
                                  __global const uint* node_count, __global const uint* node_chunk,
                                  uint nodes, __global const KdLargeNode* node,
                                  __global const float* tight_box, __global uint* chunk_bins) {
    __local uint counts[KDRAY_BIN_VALUES];
    const uint c = get_group_id(0), l = get_local_id(0), g = get_local_size(0);
    for (uint k = l; k < KDRAY_BIN_VALUES; k += g) counts[k] = 0;
    barrier(CLK_LOCAL_MEM_FENCE);
    uint begin, end;
    const uint i = kd_chunk_references(c, node_start, node_count, node_chunk, nodes, &begin, &end);
    const KdBox tight = kd_bin_box(kd_box_of(node[i].box), tight_box, i);
    const float4 scale = kd_bin_scale(tight, KDRAY_LARGE_BINS);
    const float4 lo = (float4)(tight.lo, 0.0f);
    for (uint r = begin + l; r < end; r += g) {
        uint4 lo_bin, hi_bin;
        kd_large_bins(kd_load_box(ref_box, r), lo, scale, &lo_bin, &hi_bin);
        atomic_inc(&counts[lo_bin.x]);
        atomic_inc(&counts[KDRAY_LARGE_BINS + hi_bin.x]);
        atomic_inc(&counts[2 * KDRAY_LARGE_BINS + lo_bin.y]);
        atomic_inc(&counts[3 * KDRAY_LARGE_BINS + hi_bin.y]);
        atomic_inc(&counts[4 * KDRAY_LARGE_BINS + lo_bin.z]);
        atomic_inc(&counts[5 * KDRAY_LARGE_BINS + hi_bin.z]);
    }
    barrier(CLK_LOCAL_MEM_FENCE);
    __global uint* out = chunk_bins + (size_t)c * KDRAY_BIN_VALUES;
    for (uint k = l; k < KDRAY_BIN_VALUES; k += g) out[k] = counts[k];
}

/* A node's bins: the sum of its chunks' (a work-item per node and bin value, so that neighbours
 * read neighbouring words), for kd_split_large_nodes with bins_by_node. */
__kernel void kd_sum_node_bins(__global const uint* node_chunk, uint nodes,
                               __global const uint* chunk_bins, __global uint* node_bins) {
    const uint id = get_global_id(0);
    if (id >= nodes * KDRAY_BIN_VALUES) return;
    const uint i = id / KDRAY_BIN_VALUES, k = id % KDRAY_BIN_VALUES;
    uint sum = 0;
    for (uint c = node_chunk[i]; c < node_chunk[i + 1]; ++c)
        sum += chunk_bins[(size_t)c * KDRAY_BIN_VALUES + k];
    node_bins[id] = sum;
}
#endif

/* kd_classify_chunks in this shape: each work-item classifies its references (one per round),
 * and the group adds up the chunk's counts below and above. */
__kernel void kd_classify_chunk_groups(
    KdLargeLevelArgs a, __global const uint* node_ref_start, __global const uint* node_ref_count,
    __global const uint* node_chunk, __global const uint* ref_tri, __global const float* ref_box,
    __global const float* triangles, __global const KdLargeNode* large_node,
    __global const KdLargeSplit* node_split, __global uchar* ref_sides, __global float* child_box,
    __global uint* chunk_counts) {
    __local uint sum[2];
    const uint c = get_group_id(0), l = get_local_id(0), g = get_local_size(0);
    if (l < 2) sum[l] = 0;
    barrier(CLK_LOCAL_MEM_FENCE);
    uint begin, end;
    const uint i =
        kd_chunk_references(c, node_ref_start, node_ref_count, node_chunk, a.nodes, &begin, &end);
    const uint axis = node_split[i].axis;
    uint below = 0, above = 0;
    if (axis == KDRAY_LEAF_AXIS) {
        for (uint r = begin + l; r < end; r += g) ref_sides[r] = 0;
    } else {
        const float split = node_split[i].pos;
        const KdBox node = kd_box_of(large_node[i].box);
        for (uint r = begin + l; r < end; r += g) {
            /* A constant axis in each call, as in kd_classify_references. */
            uint sides;
            if (axis == 0)
                sides = kd_classify_reference(r, a.refs, 0, split, KDRAY_BELOW, node, ref_tri,
                                              ref_box, triangles, child_box);
            else if (axis == 1)
                sides = kd_classify_reference(r, a.refs, 1, split, KDRAY_BELOW, node, ref_tri,
                                              ref_box, triangles, child_box);
            else
                sides = kd_classify_reference(r, a.refs, 2, split, KDRAY_BELOW, node, ref_tri,
                                              ref_box, triangles, child_box);
            ref_sides[r] = (uchar)sides;
            below += (sides & KDRAY_BELOW) != 0;
            above += (sides & KDRAY_ABOVE) != 0;
        }
    }
    if (below) atomic_add(&sum[0], below);
    if (above) atomic_add(&sum[1], above);
    barrier(CLK_LOCAL_MEM_FENCE);
    if (l == 0) {
        chunk_counts[c] = sum[0];
        chunk_counts[a.chunks + c] = sum[1];
    }
}

/* A float as an int that orders as the float does (negative floats' bits reversed), so that
 * local int atomics can take a min or max of floats (OpenCL 1.2 has no float atomics). */
KDRAY_INLINE int kd_ordered_key(float x) {
    const int bits = as_int(x);
    return bits >= 0 ? bits : bits ^ 0x7FFFFFFF;
}
KDRAY_INLINE float kd_key_float(int key) {
    return as_float(key >= 0 ? key : key ^ 0x7FFFFFFF);
}

/* kd_distribute_chunks in this shape: a round of G references at a time, each reference's rank
 * in its child the chunk's scanned count, the counts of the rounds before, and an exclusive scan
 * of the round's flags (below in the low half-word, above in the high: a chunk holds at most
 * KDRAY_REDUCE_CHUNK references, so neither half overflows). The boxes sent to each side are
 * reduced by local atomics on ordered keys (each work-item's own union first). */
__kernel void kd_distribute_chunk_groups(
    KdLargeLevelArgs a, __global const uint* node_ref_start, __global const uint* node_ref_count,
    __global const uint* node_chunk, __global const uint* ref_tri, __global const float* ref_box,
    __global const uchar* ref_sides, __global const float* child_box,
    __global const KdLargeSplit* split, __global const uint* chunk_rank,
    __global const uint* slot_rank, __global uint* next_ref_tri, __global float* next_ref_box,
    __global uint* deep_ref_tri, __global float* deep_ref_box, __global uint* small_ref_tri,
    __global float* small_ref_box, __global uint* small_ref_root, __global uint* leaf_refs,
    __global float* side_box) {
    __local uint scratch[KDRAY_REDUCE_CHUNK];
    __local int sent_key[2 * KDRAY_BOX_FLOATS]; /* per side: lo.xyz (min), hi.xyz (max) */
    const uint c = get_group_id(0), l = get_local_id(0), g = get_local_size(0);
    const uint chunks = a.chunks, refs = a.refs, slots = 2 * a.nodes;
    uint begin, end;
    const uint i =
        kd_chunk_references(c, node_ref_start, node_ref_count, node_chunk, a.nodes, &begin, &end);
    const uint start = node_ref_start[i];
    KdBox sent[2];
    sent[0].lo = sent[1].lo = (float3)(INFINITY);
    sent[0].hi = sent[1].hi = (float3)(-INFINITY);
    if (split[i].axis == KDRAY_LEAF_AXIS) { /* the same for the whole group: no barrier skipped */
        const uint first =
            a.leaf_ref_base + kd_slot_rank(slot_rank, slots, KDRAY_SLOT_LEAF_REFS, 2 * i) - start;
        for (uint r = begin + l; r < end; r += g) leaf_refs[first + r] = ref_tri[r];
        if (l == 0) {
            kd_store_box(side_box, c, sent[0]);
            kd_store_box(side_box, chunks + c, sent[1]);
        }
        return;
    }
    for (uint k = l; k < 2 * KDRAY_BOX_FLOATS; k += g)
        sent_key[k] = kd_ordered_key(k % KDRAY_BOX_FLOATS < 3 ? INFINITY : -INFINITY);
    uint dst[2], kind[2], root[2];
    kd_child_targets(a, i, c, chunk_rank, slot_rank, dst, kind, root);
    const KdChildRefs out = {next_ref_tri,  next_ref_box,  deep_ref_tri,  deep_ref_box,
                             small_ref_tri, small_ref_box, small_ref_root};
    for (uint round = begin; round < end; round += g) {
        const uint r = round + l;
        const uint sides = r < end ? ref_sides[r] : 0u;
        const uint flags =
            ((sides & KDRAY_BELOW) ? 1u : 0u) | ((sides & KDRAY_ABOVE) ? 0x10000u : 0u);
        uint total;
        const uint before = kd_group_exclusive_scan(flags, scratch, &total);
        if (r < end) {
            const uint tri = ref_tri[r];
            for (uint side = 0; side < 2; ++side)
                if (sides & (side == 0 ? KDRAY_BELOW : KDRAY_ABOVE))
                    kd_send_reference(r, refs, tri, sides, side,
                                      dst[side] + (side == 0 ? before & 0xFFFFu : before >> 16),
                                      kind[side], root[side], ref_box, child_box, &out, sent);
        }
        dst[0] += total & 0xFFFFu;
        dst[1] += total >> 16;
    }
    /* The scans' barriers ordered sent_key's initialisation before this (a chunk has at least
     * one round). */
    for (uint side = 0; side < 2; ++side) {
        __local int* key = sent_key + side * KDRAY_BOX_FLOATS;
        if (sent[side].lo.x <= sent[side].hi.x) { /* not empty */
            atomic_min(&key[0], kd_ordered_key(sent[side].lo.x));
            atomic_min(&key[1], kd_ordered_key(sent[side].lo.y));
            atomic_min(&key[2], kd_ordered_key(sent[side].lo.z));
            atomic_max(&key[3], kd_ordered_key(sent[side].hi.x));
            atomic_max(&key[4], kd_ordered_key(sent[side].hi.y));
            atomic_max(&key[5], kd_ordered_key(sent[side].hi.z));
        }
    }
    barrier(CLK_LOCAL_MEM_FENCE);
    for (uint k = l; k < 2 * KDRAY_BOX_FLOATS; k += g) {
        const uint side = k / KDRAY_BOX_FLOATS;
        side_box[((size_t)side * chunks + c) * KDRAY_BOX_FLOATS + k % KDRAY_BOX_FLOATS] =
            kd_key_float(sent_key[k]);
    }
}

#endif /* KDRAY_BUILD_LARGE_GROUPS_CL */
