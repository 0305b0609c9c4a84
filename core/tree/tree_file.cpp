#include "core/tree/tree_file.h"

#include <cstring>
#include <fstream>
#include <iterator>
#include <string_view>
#include <vector>

#include "core/error.h"
#include "core/io/atomic_file.h"
#include "core/io/input_file.h"
#include "core/tree/tree_check.h"

namespace kdray {
namespace {

constexpr char kMagic[8] = {'K', 'D', 'R', 'A', 'Y', 'T', 'R', 'E'};

class Writer {
  public:
    template <typename T>
    void put(const T& value) {
        const char* p = reinterpret_cast<const char*>(&value);
        bytes_.insert(bytes_.end(), p, p + sizeof(T));
    }
    void put_string(const std::string& s) {
        put(std::uint32_t(s.size()));
        bytes_.insert(bytes_.end(), s.begin(), s.end());
    }
    template <typename T>
    void put_array(const std::vector<T>& v) {
        put(std::uint64_t(v.size()));
        const char* p = reinterpret_cast<const char*>(v.data());
        bytes_.insert(bytes_.end(), p, p + v.size() * sizeof(T));
    }
    std::string_view bytes() const { return {bytes_.data(), bytes_.size()}; }

  private:
    std::vector<char> bytes_;
};

class Reader {
  public:
    Reader(std::vector<char> bytes, std::string name)
        : bytes_(std::move(bytes)), name_(std::move(name)) {}
    template <typename T>
    T get() {
        T value;
        need(sizeof(T));
        std::memcpy(&value, bytes_.data() + at_, sizeof(T));
        at_ += sizeof(T);
        return value;
    }
    std::string get_string() {
        auto n = get<std::uint32_t>();
        need(n);
        std::string s(bytes_.data() + at_, n);
        at_ += n;
        return s;
    }
    template <typename T>
    std::vector<T> get_array() {
        auto n = get<std::uint64_t>();
        if (n > (bytes_.size() - at_) / sizeof(T)) truncated();
        std::vector<T> v(n);
        // An empty vector's data() may be null, which memcpy must not get even for 0 bytes
        // (fuzz_tree_file found it: a tree file with no leaf indices).
        if (n > 0) std::memcpy(v.data(), bytes_.data() + at_, n * sizeof(T));
        at_ += n * sizeof(T);
        return v;
    }
    bool at_end() const { return at_ == bytes_.size(); }

  private:
    void need(std::size_t n) {
        if (n > bytes_.size() - at_) truncated();
    }
    [[noreturn]] void truncated() { throw Error(name_ + ": kd-tree file is truncated"); }

    std::vector<char> bytes_;
    std::string name_;
    std::size_t at_ = 0;
};

/// FNV-1a, 64 bits: the scene hash, and the checksum that ends a tree file.
std::uint64_t fnv1a(std::string_view bytes) {
    std::uint64_t h = 14695981039346656037ull;
    for (const char c : bytes) {
        h ^= static_cast<unsigned char>(c);
        h *= 1099511628211ull;
    }
    return h;
}

}  // namespace

std::uint64_t tree_file_checksum(std::string_view bytes) {
    return fnv1a(bytes);
}

std::uint64_t scene_hash(const Scene& scene) {
    return fnv1a({reinterpret_cast<const char*>(scene.triangles.data()),
                  scene.triangles.size() * sizeof(float)});
}

void write_tree_file(const std::filesystem::path& path, const KdTree& tree, const Scene& scene) {
    Writer w;
    for (char c : kMagic) w.put(c);
    w.put(kTreeFileVersion);
    w.put_string(std::filesystem::absolute(scene.path).lexically_normal().string());
    w.put(std::uint64_t(scene.triangle_count()));
    w.put(scene_hash(scene));
    w.put_string(tree.builder);
    const BuildParams& p = tree.params;
    w.put(p.costs.traversal);
    w.put(p.costs.intersection);
    w.put(p.empty_bonus);
    w.put(std::int32_t(p.large_node_threshold));
    w.put(p.empty_space_ratio);
    w.put(std::int32_t(p.large_split_bins));
    w.put(std::int32_t(p.small_reclip_refs));
    w.put(std::int32_t(p.small_leaf_refs));
    w.put(std::int32_t(p.small_split_bins));
    w.put(std::int32_t(p.max_depth));
    for (int a = 0; a < 3; ++a) w.put(tree.bounds.lo[a]);
    for (int a = 0; a < 3; ++a) w.put(tree.bounds.hi[a]);
    w.put_array(tree.nodes);
    w.put_array(tree.leaf_indices);
    w.put(fnv1a(w.bytes()));
    write_file_atomically(path, w.bytes());
}

TreeFile read_tree_file(const std::filesystem::path& path) {
    return parse_tree_file(read_input_file(path, "kd-tree file"), path);
}

TreeFile parse_tree_file(std::string_view text, const std::filesystem::path& path) {
    if (text.size() < sizeof(kMagic) || std::memcmp(text.data(), kMagic, sizeof(kMagic)) != 0)
        throw Error(path.string() + ": not a kdray kd-tree file");
    // The version comes first, so that an older file is named as such rather than as corrupt.
    std::uint32_t file_version = 0;
    if (text.size() >= sizeof(kMagic) + sizeof(file_version))
        std::memcpy(&file_version, text.data() + sizeof(kMagic), sizeof(file_version));
    if (file_version != kTreeFileVersion)
        throw Error(path.string() + ": kd-tree file version " + std::to_string(file_version) +
                    ", this kdray reads version " + std::to_string(kTreeFileVersion));
    std::uint64_t checksum = 0;
    if (text.size() < sizeof(kMagic) + sizeof(file_version) + sizeof(checksum))
        throw Error(path.string() + ": kd-tree file is truncated");
    const std::string_view body(text.data(), text.size() - sizeof(checksum));
    std::memcpy(&checksum, text.data() + body.size(), sizeof(checksum));
    if (checksum != fnv1a(body))
        throw Error(path.string() + ": kd-tree file is corrupt (its checksum does not match)");
    std::vector<char> bytes(body.begin(), body.end());
    Reader r(std::move(bytes), path.string());
    // Magic and version, checked above.
    for (std::size_t i = 0; i < sizeof(kMagic); ++i) r.get<char>();
    r.get<std::uint32_t>();
    TreeFile f;
    f.scene_path = r.get_string();
    f.scene_triangles = r.get<std::uint64_t>();
    f.scene_hash = r.get<std::uint64_t>();
    f.tree.builder = r.get_string();
    BuildParams& p = f.tree.params;
    p.costs.traversal = r.get<float>();
    p.costs.intersection = r.get<float>();
    p.empty_bonus = r.get<float>();
    p.large_node_threshold = r.get<std::int32_t>();
    p.empty_space_ratio = r.get<float>();
    p.large_split_bins = r.get<std::int32_t>();
    p.small_reclip_refs = r.get<std::int32_t>();
    p.small_leaf_refs = r.get<std::int32_t>();
    p.small_split_bins = r.get<std::int32_t>();
    p.max_depth = r.get<std::int32_t>();
    for (int a = 0; a < 3; ++a) f.tree.bounds.lo[a] = r.get<float>();
    for (int a = 0; a < 3; ++a) f.tree.bounds.hi[a] = r.get<float>();
    f.tree.nodes = r.get_array<KdNode>();
    f.tree.leaf_indices = r.get_array<kd_u32>();
    if (!r.at_end()) throw Error(path.string() + ": kd-tree file has trailing bytes");
    // A sound checksum says the bytes are the ones written; what was written must still be a
    // tree kdray can use: parameters the builders accept, every offset and index in range.
    try {
        validate_build_params(p);
    } catch (const Error& e) {
        throw Error(path.string() + ": kd-tree file: " + e.what());
    }
    if (f.tree.builder != "opencl" && f.tree.builder != "reference")
        throw Error(path.string() + ": kd-tree file names an unknown builder");
    const std::vector<std::string> problems = check_tree_layout(f.tree, f.scene_triangles, 1);
    if (!problems.empty())
        throw Error(path.string() + ": kd-tree file holds an invalid tree: " + problems.front());
    return f;
}

}  // namespace kdray
