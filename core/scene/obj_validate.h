// obj_validate.h — kdray's own pre-scan of an OBJ file, run before tinyobjloader parses it.
//
// Debian's tinyobjloader (2.0.0rc10) accepts inputs that would silently corrupt a scene: it reads
// `nan`/`inf` text as 0, lets `1e999` overflow to inf, only warns about face indices past the end,
// and never checks negative (relative) indices against the vertices defined so far. The pre-scan
// rejects all of these with an Error that names the file, the line and the problem, so that
// everything tinyobjloader later sees is well formed.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace kdray {

/// A material library named by an `mtllib` line.
struct MtlReference {
    std::string name;
    std::size_t line = 0;
};

/// What the pre-scan learned about a valid OBJ text.
struct ObjPrescan {
    std::size_t vertices = 0;   // `v` lines
    std::size_t normals = 0;    // `vn` lines
    std::size_t texcoords = 0;  // `vt` lines
    std::size_t faces = 0;      // `f` lines
    /// Triangles after fan triangulation of every face (a quad gives 2, an n-gon n - 2).
    std::size_t triangles = 0;
    /// x y z of every `v` line in double, exactly as the file writes them (correctly rounded):
    /// the scene's own coordinates, before SceneFrame rounds them to float in its frame.
    /// tinyobjloader's float vertices are only for its triangulation.
    std::vector<double> positions;
    std::vector<MtlReference> material_libraries;
};

/// Checks an OBJ file's text: every `v` line has 3, 4 or 6 finite numbers that fit a float, every
/// `vt` line 1 to 3 and every `vn` line 3 of them, every
/// face has at least 3 vertices whose v/vt/vn indices name existing attributes (a positive index
/// at most the file's count, a negative one at most the count defined before its line, never 0),
/// statements are known OBJ keywords and the text holds no control bytes. `name` is the file name
/// the Errors begin with ("NAME:LINE: ...").
ObjPrescan validate_obj(std::string_view text, const std::string& name);

}  // namespace kdray
