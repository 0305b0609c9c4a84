// tree_file.h — kd-trees saved to disk (`kdray build -o`): a versioned little-endian binary file
// that records which scene the tree belongs to (its path, triangle count and a hash of the
// triangle data), so a tree is never used with a scene it was not built for.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

#include "core/scene/scene.h"
#include "core/tree/tree.h"

namespace kdray {

/// 3: a checksum (FNV-1a of every byte before it) ends the file. 4: the small stage's re-clip and
/// leaf sizes follow the large-node bins among the build parameters. 5: then its bins.
inline constexpr std::uint32_t kTreeFileVersion = 5;

struct TreeFile {
    KdTree tree;
    std::string scene_path;
    std::uint64_t scene_triangles = 0;
    std::uint64_t scene_hash = 0;
};

/// FNV-1a over the triangle floats' bytes: identifies the geometry a tree was built over.
std::uint64_t scene_hash(const Scene& scene);

void write_tree_file(const std::filesystem::path& path, const KdTree& tree, const Scene& scene);
/// Throws Error naming the file when it is not a kdray tree, of another version, truncated,
/// corrupt (checksum), or holds parameters or a tree layout kdray would not build (every node
/// offset and leaf index is checked).
TreeFile read_tree_file(const std::filesystem::path& path);
/// The checksum that ends a tree file: FNV-1a (64 bits) of every byte before it.
std::uint64_t tree_file_checksum(std::string_view bytes);
/// The same from a tree file's bytes already in memory; `path` names it in errors.
TreeFile parse_tree_file(std::string_view bytes, const std::filesystem::path& path);

}  // namespace kdray
