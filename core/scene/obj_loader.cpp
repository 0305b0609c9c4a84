// obj_loader.cpp — load_obj: an OBJ file (and its MTL libraries) into a Scene.
//
// The file is read once and pre-scanned by validate_obj (obj_validate.h), which rejects what
// Debian's tinyobjloader would silently get wrong; then tinyobjloader parses the same bytes with
// triangulate = true, and the triangles are numbered in the order it lists them, shape by shape,
// face by face, as conventions.md requires.
#include <tiny_obj_loader.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <istream>
#include <limits>
#include <map>
#include <memory>
#include <set>
#include <streambuf>
#include <string_view>
#include <tuple>

#include "core/error.h"
#include "core/io/input_file.h"
#include "core/scene/mtl_prepare.h"
#include "core/scene/obj_validate.h"
#include "core/scene/scene.h"
#include "core/scene/texture_loader.h"

namespace kdray {
namespace {

/// A read-only stream over bytes already in memory (no copy of a file of tens of megabytes).
class MemoryStreamBuffer : public std::streambuf {
  public:
    explicit MemoryStreamBuffer(std::string_view bytes) {
        char* begin = const_cast<char*>(bytes.data());  // never written: get area only
        setg(begin, begin, begin + bytes.size());
    }
};

struct ParsedObj {
    tinyobj::attrib_t attrib;
    std::vector<tinyobj::shape_t> shapes;
    std::vector<tinyobj::material_t> materials;
    std::string warnings;
};

/// Where an `mtllib` name points: an absolute name is itself, a relative one is in the OBJ's
/// folder (tinyobjloader's own reader would join even an absolute name onto the folder).
std::filesystem::path library_path(const std::filesystem::path& obj_folder,
                                   const std::string& name) {
    const std::filesystem::path library(name);
    return library.is_absolute() ? library : obj_folder / library;
}

/// The MTL libraries as kdray reads every input (input_file.h: regular files only, bounded)
/// and pre-scans them (mtl_prepare.h) before tinyobjloader's LoadMtl parses what the pass returns.
/// A library that does not exist is not loaded (load_obj has warned about it, with its line).
class MtlLibraryReader : public tinyobj::MaterialReader {
  public:
    explicit MtlLibraryReader(std::filesystem::path obj_folder) : folder_(std::move(obj_folder)) {}

    bool operator()(const std::string& name, std::vector<tinyobj::material_t>* materials,
                    std::map<std::string, int>* material_map, std::string* warn,
                    std::string* err) override {
        const std::filesystem::path path = library_path(folder_, name);
        std::error_code ec;
        if (!std::filesystem::exists(path, ec)) {
            if (warn) *warn += "Material file [ " + name + " ] not found\n";
            return false;
        }
        const std::string text =
            prepare_mtl(read_input_file(path, "MTL file", kMtlSizeLimit), path.string());
        MemoryStreamBuffer buffer(text);
        std::istream in(&buffer);
        tinyobj::LoadMtl(material_map, materials, &in, warn, err);
        return true;
    }

  private:
    // Material libraries are a few kilobytes; 256 MiB is far past any real one.
    static constexpr std::uint64_t kMtlSizeLimit = std::uint64_t(256) << 20;
    std::filesystem::path folder_;
};

/// tinyobjloader's parse of the OBJ text `text` of file `path`: what ObjReader::ParseFromFile
/// does (triangulate, no vertex colours), from the bytes in memory instead of a second read of
/// the file, with the MTL libraries read by MtlLibraryReader.
ParsedObj parse_obj_text(std::string_view text, const std::filesystem::path& path) {
    const std::string name = path.string();
    MtlLibraryReader mtl_reader(path.parent_path());
    MemoryStreamBuffer buffer(text);
    std::istream in(&buffer);
    ParsedObj obj;
    std::string error;
    if (!tinyobj::LoadObj(&obj.attrib, &obj.shapes, &obj.materials, &obj.warnings, &error, &in,
                          &mtl_reader, /*triangulate=*/true, /*default_vcols_fallback=*/false)) {
        while (!error.empty() && (error.back() == '\n' || error.back() == '\r')) error.pop_back();
        std::replace(error.begin(), error.end(), '\n', ';');
        throw Error(name + ": " + (error.empty() ? "tinyobjloader cannot parse the file" : error));
    }
    return obj;
}

Vec3 vec3(const tinyobj::real_t* v) {
    return {static_cast<float>(v[0]), static_cast<float>(v[1]), static_cast<float>(v[2])};
}

/// scene.vertex_normals from each corner's `vn` index into normals (-1: none): the normal made
/// unit length, in double; a corner without one, or with a zero normal, gets its triangle's
/// geometric normal, so that it shades flat. The OBJ's normals are finite (validate_obj).
void set_vertex_normals(Scene& scene, const std::vector<int>& corner_normal,
                        const std::vector<tinyobj::real_t>& normals) {
    const std::size_t n = scene.triangle_count();
    scene.vertex_normals.resize(n * KDRAY_FLOATS_PER_TRIANGLE);
    auto unit = [](const double* v, float* out) {
        const double len = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        if (!(len > 0.0) || !std::isfinite(len)) return false;
        for (int a = 0; a < 3; ++a) out[a] = static_cast<float>(v[a] / len);
        return true;
    };
    for (std::size_t t = 0; t < n; ++t) {
        double geometric[3];
        triangle_cross_double(&scene.triangles[t * KDRAY_FLOATS_PER_TRIANGLE], geometric);
        for (int corner = 0; corner < 3; ++corner) {
            float* out = &scene.vertex_normals[t * KDRAY_FLOATS_PER_TRIANGLE + 3 * corner];
            const int index = corner_normal[3 * t + corner];
            if (index >= 0 && 3 * std::size_t(index) + 2 < normals.size()) {
                const double given[3] = {normals[3 * std::size_t(index)],
                                         normals[3 * std::size_t(index) + 1],
                                         normals[3 * std::size_t(index) + 2]};
                if (unit(given, out)) continue;
            }
            // A zero-area triangle has no normal either; it is never hit.
            if (!unit(geometric, out)) std::fill(out, out + 3, 0.0f);
        }
    }
}

/// scene.frame fitted to the bounds of the triangles' corners (in double, the file's own
/// coordinates), and scene.triangles: each corner's position in that frame, rounded to float once.
void place_in_frame(Scene& scene, const std::vector<std::size_t>& corner_vertices,
                    const std::vector<double>& positions) {
    const double inf = std::numeric_limits<double>::infinity();
    DVec3 lo{inf, inf, inf}, hi{-inf, -inf, -inf};
    for (const std::size_t v : corner_vertices)
        for (int a = 0; a < 3; ++a) {
            lo[a] = std::min(lo[a], positions[3 * v + a]);
            hi[a] = std::max(hi[a], positions[3 * v + a]);
        }
    scene.frame = SceneFrame::fit(lo, hi, scene.path.string());
    scene.triangles.resize(corner_vertices.size() * 3);
    for (std::size_t c = 0; c < corner_vertices.size(); ++c) {
        const double* p = &positions[3 * corner_vertices[c]];
        const Vec3 f = scene.frame.point({p[0], p[1], p[2]});
        for (int a = 0; a < 3; ++a) scene.triangles[3 * c + a] = f[a];
    }
}

Material to_material(const tinyobj::material_t& m) {
    Material out;
    out.name = m.name;
    out.ambient = vec3(m.ambient);
    out.diffuse = vec3(m.diffuse);
    out.specular = vec3(m.specular);
    out.shininess = static_cast<float>(m.shininess);
    out.ior = static_cast<float>(m.ior);
    // tinyobjloader already folds Tr into dissolve (d = 1 - Tr when only Tr is given, d when
    // both are).
    out.dissolve = static_cast<float>(m.dissolve);
    out.transmission = vec3(m.transmittance);
    out.emission = vec3(m.emission);
    out.illum = m.illum;
    return out;
}

/// One warning for each MTL statement of `m` that kdray reads but does not simulate, so that a
/// scene never renders differently from what its files ask for without a word: texture and
/// bump maps (map_Kd and map_Ka are simulated: TextureLoader), PBR parameters, a transmission
/// filter on an opaque material, and every statement tinyobjloader does not know (decal, sharpness,
/// ...). Once per material and statement, however many faces use it.
void warn_unsimulated(const tinyobj::material_t& m, const Material& material,
                      const std::string& file, std::vector<std::string>& warnings) {
    const auto warn = [&](const std::string& statement, const std::string& what) {
        warnings.push_back(file + ": material '" + m.name + "': " + statement +
                           " is not simulated (" + what + ")");
    };
    const struct {
        const std::string& name;
        const char* statement;
        const char* what;
    } maps[] = {
        {m.specular_texname, "map_Ks", "Ks renders untextured"},
        {m.specular_highlight_texname, "map_Ns", "Ns renders untextured"},
        {m.bump_texname, "map_bump/bump", "the surface renders unbumped"},
        {m.displacement_texname, "disp", "the surface renders undisplaced"},
        {m.alpha_texname, "map_d", "d renders untextured"},
        {m.reflection_texname, "refl", "no reflection map"},
        {m.roughness_texname, "map_Pr", "PBR roughness"},
        {m.metallic_texname, "map_Pm", "PBR metallic"},
        {m.sheen_texname, "map_Ps", "PBR sheen"},
        {m.emissive_texname, "map_Ke", "Ke renders untextured"},
        {m.normal_texname, "norm", "the surface renders without its normal map"},
    };
    for (const auto& map : maps)
        if (!map.name.empty()) warn(std::string(map.statement) + " '" + map.name + "'", map.what);
    // The texture lookup reads a map at the hit's vt as it is: `map_Kd -s 4 4 1 tex.png` (tiled)
    // rendered unscaled without a word. tinyobjloader parses the options; any not at its default
    // is named, once per map.
    for (const auto& [texname, texopt, statement] :
         {std::tuple{&m.diffuse_texname, &m.diffuse_texopt, "map_Kd"},
          std::tuple{&m.ambient_texname, &m.ambient_texopt, "map_Ka"}}) {
        if (texname->empty()) continue;
        const tinyobj::texture_option_t& o = *texopt;
        auto g = [](double v) {
            char text[32];
            std::snprintf(text, sizeof text, "%g", v);
            return std::string(text);
        };
        auto three = [&](const tinyobj::real_t* v) {
            return g(v[0]) + " " + g(v[1]) + " " + g(v[2]);
        };
        std::string options;
        auto add = [&](bool set, const std::string& option) {
            if (set) options += (options.empty() ? "" : ", ") + option;
        };
        add(o.scale[0] != 1 || o.scale[1] != 1 || o.scale[2] != 1, "-s " + three(o.scale));
        add(o.origin_offset[0] != 0 || o.origin_offset[1] != 0 || o.origin_offset[2] != 0,
            "-o " + three(o.origin_offset));
        add(o.turbulence[0] != 0 || o.turbulence[1] != 0 || o.turbulence[2] != 0,
            "-t " + three(o.turbulence));
        add(o.clamp, "-clamp on");
        add(o.brightness != 0 || o.contrast != 1, "-mm " + g(o.brightness) + " " + g(o.contrast));
        add(!o.blendu, "-blendu off");
        add(!o.blendv, "-blendv off");
        add(o.sharpness != 1, "-boost " + g(o.sharpness));
        if (!options.empty())
            warn(std::string(statement) + " '" + *texname + "' option " + options,
                 "the texture renders as if the option were not given");
    }
    const struct {
        tinyobj::real_t value;
        const char* statement;
    } pbr[] = {{m.roughness, "Pr"},
               {m.metallic, "Pm"},
               {m.sheen, "Ps"},
               {m.clearcoat_thickness, "Pc"},
               {m.clearcoat_roughness, "Pcr"},
               {m.anisotropy, "aniso"},
               {m.anisotropy_rotation, "anisor"}};
    for (const auto& p : pbr)
        if (p.value != 0) warn(p.statement, "PBR parameter");
    // Tf 0 0 0 (absent) and 1 1 1 (the common "no filter") filter nothing on an opaque material.
    const Vec3 tf = material.transmission;
    if (!material.transmits() && !(tf == Vec3{0, 0, 0}) && !(tf == Vec3{1, 1, 1}))
        warn("Tf", "the material is opaque: nothing is transmitted to filter");
    for (const auto& [statement, value] : m.unknown_parameter)
        warn(statement, "kdray does not read this statement");
}

bool starts_with(std::string_view s, std::string_view prefix) {
    return s.substr(0, prefix.size()) == prefix;
}

/// tinyobjloader's warnings as one-line scene warnings, each prefixed with the file. Lines that
/// the loader's own missing-library warnings already cover are dropped, the per-material
/// "both d and Tr" notes become one line, and repeats are kept once.
std::vector<std::string> convert_warnings(const std::string& warnings, const std::string& file,
                                          bool library_missing) {
    std::vector<std::string> out;
    std::set<std::string> seen;
    std::set<std::string> d_and_tr;
    std::size_t start = 0;
    while (start < warnings.size()) {
        std::size_t end = warnings.find('\n', start);
        if (end == std::string::npos) end = warnings.size();
        std::string_view line(warnings.data() + start, end - start);
        start = end + 1;
        while (!line.empty() && (line.front() == ' ' || line.front() == '\t' ||
                                 line.front() == '.' || line.front() == '\r'))
            line.remove_prefix(1);
        while (!line.empty() && (line.back() == ' ' || line.back() == '\r')) line.remove_suffix(1);
        if (line.empty()) continue;
        if (starts_with(line, "Material file [") || starts_with(line, "Failed to load material"))
            continue;
        if (library_missing && starts_with(line, "material [")) continue;
        if (starts_with(line, "Both `d` and `Tr`")) {
            d_and_tr.insert(std::string(line.substr(0, line.find(". Use"))));
            continue;
        }
        std::string text = file + ": " + std::string(line);
        if (seen.insert(text).second) out.push_back(std::move(text));
    }
    if (!d_and_tr.empty())
        out.push_back(file + ": " + std::to_string(d_and_tr.size()) +
                      " material(s) set both d and Tr; the value of d is used");
    return out;
}

}  // namespace

Scene load_obj(const std::filesystem::path& path) {
    const std::string name = path.string();

    // Pre-scan: everything tinyobjloader would silently accept must fail here, with a line.
    const std::string text = read_input_file(path, "OBJ file");
    const ObjPrescan prescan = validate_obj(text, name);

    Scene scene;
    scene.path = path;

    // Missing material libraries are a warning, not an error: the scene still has geometry.
    // tinyobjloader looks them up beside the OBJ file, and so does this check.
    bool library_missing = false;
    for (const MtlReference& library : prescan.material_libraries) {
        const std::filesystem::path candidate = library_path(path.parent_path(), library.name);
        const std::string where =
            name + ":" + std::to_string(library.line) + ": material library '" + library.name + "'";
        std::error_code ec;
        const std::filesystem::file_status status = std::filesystem::status(candidate, ec);
        if (!std::filesystem::exists(status)) {
            library_missing = true;
            scene.warnings.push_back(where + " not found; using a grey default material");
        } else if (!std::filesystem::is_regular_file(status)) {
            throw Error(where + " (" + candidate.string() + ") is not a regular file");
        }
    }

    // tinyobjloader parses the bytes the pre-scan read (one read of the file per load), as its
    // ObjReader::ParseFromFile would parse the file: triangulated, MTL files beside the OBJ.
    const ParsedObj obj = parse_obj_text(text, path);
    for (std::string& w : convert_warnings(obj.warnings, name, library_missing))
        scene.warnings.push_back(std::move(w));

    // Texture files resolve relative to the MTL file's folder (that of the first library when
    // there are several: tinyobjloader does not say which library a material came from).
    const std::filesystem::path mtl_folder =
        prescan.material_libraries.empty()
            ? path.parent_path()
            : library_path(path.parent_path(), prescan.material_libraries.front().name)
                  .parent_path();
    TextureLoader textures(scene, mtl_folder, name);
    for (const tinyobj::material_t& m : obj.materials) {
        scene.materials.push_back(to_material(m));
        Material& material = scene.materials.back();
        if (!m.diffuse_texname.empty())
            material.diffuse_texture = textures.load(m.name, "map_Kd", m.diffuse_texname);
        if (!m.ambient_texname.empty())
            material.ambient_texture = textures.load(m.name, "map_Ka", m.ambient_texname);
        warn_unsimulated(m, material, name, scene.warnings);
        // BART writes Ni 0 for opaque materials, and for some that transmit (the Robots' m49);
        // those refract with Ni 1, which bends nothing: said, not silent.
        if (material.transmits() && !(material.ior > 0.0f))
            scene.warnings.push_back(name + ": material '" + material.name +
                                     "' transmits light but has no index of refraction (Ni " +
                                     std::to_string(material.ior) + "); it refracts with Ni 1");
    }
    const auto default_material = static_cast<kd_u32>(scene.materials.size());
    bool default_needed = false;

    // Triangles, numbered shape by shape and face by face in tinyobjloader's order; each
    // corner's vertex is the pre-scan's double position of the same `v` line.
    if (obj.attrib.vertices.size() != prescan.positions.size())
        throw Error(name + ": tinyobjloader read " +
                    std::to_string(obj.attrib.vertices.size() / 3) +
                    " vertices where kdray's pre-scan read " +
                    std::to_string(prescan.positions.size() / 3));
    std::vector<std::size_t> corner_vertices;
    corner_vertices.reserve(prescan.triangles * 3);
    scene.material_ids.reserve(prescan.triangles);
    // Each corner's `vn` index (-1: none), made into scene.vertex_normals once all are known.
    std::vector<int> normal_indices;
    bool any_normal = false;
    // Each triangle's vt corners (u NaN where a corner has none), kept once any face has vt.
    const std::vector<tinyobj::real_t>& uvs = obj.attrib.texcoords;
    std::vector<float> texcoords;
    bool any_texcoord = false;
    for (const tinyobj::shape_t& shape : obj.shapes) {
        const tinyobj::mesh_t& mesh = shape.mesh;
        std::size_t offset = 0;
        for (std::size_t f = 0; f < mesh.num_face_vertices.size(); ++f) {
            const std::size_t count = mesh.num_face_vertices[f];
            const int material = f < mesh.material_ids.size() ? mesh.material_ids[f] : -1;
            kd_u32 id = default_material;
            if (material >= 0 && static_cast<std::size_t>(material) < scene.materials.size())
                id = static_cast<kd_u32>(material);
            else
                default_needed = true;
            // With triangulate = true every face has 3 vertices; a fan keeps any other safe.
            for (std::size_t k = 1; k + 1 < count; ++k) {
                int corner_normal[3];
                int c = 0;
                for (std::size_t corner : {std::size_t{0}, k, k + 1}) {
                    const tinyobj::index_t& index = mesh.indices[offset + corner];
                    corner_vertices.push_back(static_cast<std::size_t>(index.vertex_index));
                    corner_normal[c++] = index.normal_index;
                    any_normal = any_normal || index.normal_index >= 0;
                }
                normal_indices.insert(normal_indices.end(), corner_normal, corner_normal + 3);
                float uv[6];
                bool textured = true;
                c = 0;
                for (std::size_t corner : {std::size_t{0}, k, k + 1}) {
                    const int t = mesh.indices[offset + corner].texcoord_index;
                    textured = textured && t >= 0 && 2 * std::size_t(t) + 1 < uvs.size();
                    uv[c++] = textured ? float(uvs[2 * std::size_t(t)]) : 0.0f;
                    uv[c++] = textured ? float(uvs[2 * std::size_t(t) + 1]) : 0.0f;
                }
                if (!textured) uv[0] = std::nanf("");
                any_texcoord = any_texcoord || textured;
                texcoords.insert(texcoords.end(), uv, uv + 6);
                scene.material_ids.push_back(id);
            }
            offset += count;
        }
    }
    if (default_needed) scene.materials.push_back(Material{.name = "default"});
    if (corner_vertices.empty()) throw Error(name + ": the scene has no triangles");
    place_in_frame(scene, corner_vertices, prescan.positions);
    if (any_normal) set_vertex_normals(scene, normal_indices, obj.attrib.normals);
    if (any_texcoord) scene.texcoords = std::move(texcoords);

    if (scene.triangle_count() != prescan.triangles)
        scene.warnings.push_back(
            name + ": tinyobjloader made " + std::to_string(scene.triangle_count()) +
            " triangles from faces that fan-triangulate to " + std::to_string(prescan.triangles));

    // Zero-area triangles are kept, counted for the statistics and made unhittable.
    collapse_zero_area_triangles(scene);
    return scene;
}

}  // namespace kdray
