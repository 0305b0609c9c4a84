#include "core/scene/texture_loader.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <system_error>
#include <vector>

#include "core/error.h"
#include "core/io/image_codec.h"
#include "core/io/input_file.h"

namespace kdray {
namespace {

namespace fs = std::filesystem;

std::string lower(std::string s) {
    std::transform(s.begin(), s.end(), s.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    return s;
}

/// The IEC 61966-2-1 decoding of an sRGB value in [0, 1].
float srgb_decode(float encoded) {
    return encoded <= 0.04045f ? encoded / 12.92f : std::pow((encoded + 0.055f) / 1.055f, 2.4f);
}

}  // namespace

/// `name` in the MTL's folder, or the file there whose name matches it but for case (Sponza's
/// MTL names 00_SKAP.JPG for 00_skap.JPG); empty when there is none. Whatever it is (a FIFO, a
/// device), read_image then refuses it by name rather than this calling it missing.
fs::path TextureLoader::resolve(const std::string& name) {
    std::error_code ec;
    const fs::path exact = folder_ / name;
    if (fs::exists(exact, ec) && !fs::is_directory(exact, ec)) return exact;
    // An OBJ named without a folder (`kdray render scene.obj`) has its textures in ".", which
    // a directory_iterator over "" would not list.
    const fs::path dir = exact.parent_path().empty() ? fs::path(".") : exact.parent_path();
    auto [folder, unlisted] = folders_.try_emplace(dir);
    if (unlisted)
        for (const fs::directory_entry& entry : fs::directory_iterator(dir, ec))
            if (!entry.is_directory(ec))
                folder->second.emplace(lower(entry.path().filename().string()), entry.path());
    const auto found = folder->second.find(lower(exact.filename().string()));
    return found != folder->second.end() ? found->second : fs::path();
}

void TextureLoader::warn(Named& named) const {
    std::string text = where_ + ": material '" + named.materials.front() + "'";
    if (named.materials.size() > 1)
        text += " (and " + std::to_string(named.materials.size() - 1) + " more that name it)";
    text += ": ";
    for (std::size_t k = 0; k < named.statements.size(); ++k)
        text += (k == 0                             ? ""
                 : k + 1 == named.statements.size() ? " and "
                                                    : ", ") +
                named.statements[k];
    text += " '" + named.name + "' " + named.why +
            (named.materials.size() > 1 ? "; they render" : "; it renders") + " untextured";
    scene_.warnings[named.warning] = std::move(text);
}

int TextureLoader::load(const std::string& material, const std::string& statement,
                        const std::string& file) {
    auto [it, is_new] = named_.try_emplace(file);
    Named& named = it->second;
    const auto remember = [](std::vector<std::string>& list, const std::string& value) {
        if (std::find(list.begin(), list.end(), value) == list.end()) list.push_back(value);
    };
    if (!is_new) {
        if (named.id < 0) {
            remember(named.materials, material);
            remember(named.statements, statement);
            warn(named);
        }
        return named.id;
    }
    const fs::path path = resolve(file);
    if (path.empty())
        named.why = "not found in " +
                    (folder_.empty() ? std::string("the current directory") : folder_.string());
    else
        named.id = load_path(path, named.why);
    if (named.id >= 0 && !named.why.empty())
        // Loaded, with what the image library printed while it decoded the file.
        scene_.warnings.push_back(where_ + ": material '" + material + "': " + statement + " '" +
                                  file + "': " + named.why);
    if (named.id < 0) {
        named.name = file;
        named.materials = {material};
        named.statements = {statement};
        named.warning = scene_.warnings.size();
        scene_.warnings.emplace_back();
        warn(named);
    }
    return named.id;
}

/// The texture of `path`, each file loaded once (names that differ but for case, or by a folder
/// part, resolve to one file); -1 with `why` when it cannot be read, and `why` what the image
/// library printed when it decoded the file with a complaint.
int TextureLoader::load_path(const fs::path& path, std::string& why) {
    if (const auto it = loaded_.find(path); it != loaded_.end()) {
        why = it->second.second;
        return it->second.first;
    }
    auto fail = [&](const std::string& reason) {
        why = "cannot be read (" + reason + ")";
        loaded_[path] = {-1, why};
        return -1;
    };
    DecodedImage image;
    try {
        image = read_image(path);
        if (!image.library_messages.empty())
            why = "the image library printed: " + image.library_messages;
    } catch (const Error& e) {
        return fail(e.what());
    }
    const int channels = image.channels;
    const std::vector<float>& pixels = image.values;
    // Integer images hold sRGB-encoded values; float images linear ones.
    const bool srgb = image.integer;
    // A texel scales Kd, whose values must be finite numbers >= 0 (mtl_prepare.cpp): a float
    // image's NaN, inf or negative texels flowed into the image, exit 0, without a word.
    if (!srgb) {
        const std::size_t count = std::size_t(image.width) * image.height * channels;
        for (std::size_t i = 0; i < count; ++i)
            if (const float v = pixels[i]; !(std::isfinite(v) && v >= 0.0f)) {
                const std::size_t pixel = i / channels;
                return fail(path.string() + ": texel (" + std::to_string(pixel % image.width) +
                            ", " + std::to_string(pixel / image.width) + ") is " +
                            std::to_string(v) + ", not a finite number >= 0");
            }
    }
    KdTexture entry{};
    entry.offset = kd_u32(scene_.texels.size() / 4);
    entry.width = kd_u32(image.width);
    entry.height = kd_u32(image.height);
    const std::size_t texels = std::size_t(image.width) * image.height;
    // Each image is within the input budgets, but a scene can name many: the atlas as a whole
    // stays within the one-input budget and its u32 texel offsets.
    const std::size_t atlas = scene_.texels.size() / 4 + texels;
    if (const std::uint64_t limit = input_size_limit();
        atlas > std::numeric_limits<kd_u32>::max() || 16 * std::uint64_t(atlas) > limit)
        return fail(path.string() + ": the scene's textures would take " +
                    std::to_string((16 * std::uint64_t(atlas)) >> 20) + " MiB, more than the " +
                    std::to_string(limit >> 20) + " MiB kdray reads of one input here");
    scene_.texels.reserve(scene_.texels.size() + 4 * texels);
    for (std::size_t i = 0; i < texels; ++i) {
        const float* p = &pixels[i * channels];
        // Grey (and grey-alpha) images give every channel their first.
        for (int c = 0; c < 3; ++c) {
            const float v = p[channels >= 3 ? c : 0];
            scene_.texels.push_back(srgb ? srgb_decode(v) : v);
        }
        scene_.texels.push_back(0.0f);
    }
    const int id = int(scene_.texture_table.size());
    scene_.texture_table.push_back(entry);
    loaded_[path] = {id, ""};
    return id;
}

}  // namespace kdray
