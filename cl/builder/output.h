// output.h — the output stage of the OpenCL builder (Zhou et al. 2008, §4.3): the node records of
// both stages become the preorder KdNode array and its leaf index list (internal to cl/builder/;
// the kernels are build_output.cl's).
#pragma once

#include "cl/builder/build_context.h"
#include "cl/builder/small_roots.h"
#include "cl/builder/small_subtrees.h"

namespace kdray::build_detail {

/// The built tree on the device: node_count KdNodes in preorder, leaf_index_count leaf indices.
struct PreorderTree {
    DeviceArray nodes, leaf_indices;
    cl_uint node_count = 0, leaf_index_count = 0;
};

/// Output stage (§4.3): subtree sizes bottom-up, preorder positions top-down, then the nodes.
PreorderTree write_preorder(BuildContext& ctx, const BuildOutput& output, const SmallRoots& small,
                            const SmallSubtrees& subtrees);

}  // namespace kdray::build_detail
