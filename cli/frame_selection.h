// frame_selection.h — which frames of an animation this run renders: `--frames START:END[:STEP]`
// (END included, either end may be left out; or N, or START-END) and `--shard I/N` (every N-th of
// those, from the I-th), so that a scheduler (a Slurm job array, GNU parallel) can spread an
// animation over many machines. Frame numbers stay the positions in the whole naturally sorted
// input list.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace kdray::cli {

/// The frame numbers to render out of `count`, in order. `frames` may also be N (one frame) or
/// START-END (Blender's habits). Throws UsageError on a malformed range or shard, naming the
/// option. When the range's END lies past the inputs, `past` (if given) says which frames are
/// missing and which are rendered; else it is left empty.
std::vector<std::size_t> select_frames(std::size_t count, const std::string& frames,
                                       const std::string& shard, std::string* past = nullptr);

}  // namespace kdray::cli
