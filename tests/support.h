// support.h — generated scenes and rays shared by the tests, including the hard cases every
// builder and tracer must survive. Each generator says why its scene is hard.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <initializer_list>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/device/kd_shared.h"
#include "core/geometry/math.h"
#include "core/io/image.h"
#include "core/render/render_file.h"
#include "core/scene/scene.h"
#include "core/tree/tree.h"

namespace kdray::test {

/// Random triangles of size ~`size` inside the cube [offset, offset + extent]^3.
Scene random_triangles(int count, std::uint32_t seed, float extent = 1.0f, float size = 0.1f,
                       float offset = 0.0f);
/// Long thin triangles (1 long, at most 0.02 wide) in random directions, centred in the unit
/// cube: each crosses many of the nodes that a small root of them splits into.
Scene long_slivers(int count, std::uint32_t seed);
/// Triangles 1e4 long and 1e-3 wide through a 10-unit box.
Scene needles(int count, std::uint32_t seed);
/// Needles 1e4 long and 1e-3 wide, all nearly along the x axis, their middles spread over the
/// unit cube, as test_intersect.cpp's needle test makes them one at a time. Seen by
/// needle_bundle_camera, every hit is one whose watertight float t was off by up to 1.5e-4
/// relative (the far corners, 5000 away along the ray's dominant axis, swamp the sum), so the
/// tracers must take the refined distance (kd_plane_distance) there.
Scene needle_bundle(int count, std::uint32_t seed);
/// A camera 1.6 from the bundle's middle, looking mostly along the needles (direction
/// (1, -0.5, 0.5)), from outside their cross-section: each needle crosses the whole image.
Camera needle_bundle_camera();
/// All triangles in the plane z = 0: the root is flat, every node below it too.
Scene planar_triangles(int count, std::uint32_t seed);
/// n^3 axis-aligned unit cubes on a lattice of spacing 2: triangles lie exactly on the candidate
/// split planes, so planar triangles and flat cells are everywhere.
Scene cube_lattice(int n);
/// `count` copies of one triangle: no split can separate them, so only the depth limit and the
/// leaf criterion stop the build.
Scene coincident_triangles(int count);
/// Random triangles mixed with zero-area ones (collapsed to a point or a segment), which are
/// referenced by the tree but must never be hit.
Scene with_zero_area(int count, std::uint32_t seed);

/// OBJ text of three UV spheres (radii 1, 0.8, 0.6; `rings` x 2 `rings` quads each, flat shaded)
/// near the origin, every coordinate multiplied by `scale` and moved by `offset` on each axis, in
/// double (17 digits): a scene that floats read on load would ruin far from the origin (spacing
/// 1.0 at 1e7) or at extreme scales (products of three coordinates overflow at 1e15).
std::string spheres_obj(double scale, double offset, int rings = 24);

/// spheres_obj's scene loaded from a file by load_obj, so through the scene frame
/// (core/scene/scene_frame.h): its triangles lie near the origin at about unit extent.
Scene load_spheres(double scale, double offset, int rings);

/// The hard scenes above by name, with the far (offset 1e5) and tiny (extent 1e-4) random scenes,
/// a needle bundle, and spheres at scales 1e-30 and 1e30 and offsets 1e7 and 1e9 loaded through
/// the scene frame. `camera`, where set, is a view of the scene's hard part for the tests that
/// render it (the needle bundle's, where a view of the whole scene would see no needle); else
/// they frame the whole scene.
struct NamedScene {
    std::string name;
    Scene scene;
    std::optional<Camera> camera;
};
std::vector<NamedScene> hard_scenes();

/// A ray from org along dir (not normalised) over [tmin, tmax].
KdRay make_ray(Vec3 org, Vec3 dir, float tmin = 0.0f, float tmax = INFINITY);

/// Rays aimed at random points of the scene's box from outside and inside it, plus rays parallel
/// to the axes and rays starting exactly on triangle-box boundaries (split plane candidates).
std::vector<KdRay> random_rays(const Scene& scene, int count, std::uint32_t seed);

/// Nearest hit by testing every triangle with the shared watertight test: the oracle.
KdHit brute_force_closest(const Scene& scene, const KdRay& ray);

/// Two hits agree when both miss, or both hit within a relative 1e-4 (conventions.md); the
/// triangle may differ on a tie.
bool hits_agree(const KdHit& a, const KdHit& b);

/// Rays traced through `tree` by the shared walk whose hits disagree with brute force's.
int count_disagreements(const KdTree& tree, const Scene& scene, const std::vector<KdRay>& rays);

/// doctest checks that `other`, a tree built another way (batches, a second pass, the other
/// small stage), is valid and node for node and leaf index for leaf index `tree`, and traces
/// 1000 rays (ray_seed) as brute force does.
void check_same_tree(const KdTree& other, const KdTree& tree, const Scene& scene,
                     std::uint32_t ray_seed);

/// An AOV's centre hits against brute force along conventions.md's camera ray of every pixel,
/// the brute force's distances mapped to the scene's units as the AOV writes them.
struct AovAgreement {
    int hits = 0;        // pixels whose brute-force ray hits
    int mismatches = 0;  // pixels where the AOV and brute force disagree (hits_agree)
};
AovAgreement aov_against_brute_force(const HitBuffer& aov, const Scene& scene, const KdView& view);

/// A small render file (48x32, one point light, the camera on a unit-cube scene such as
/// random_triangles'): for command-line tests that render anything at all.
extern const char* const kSmallRender;

/// What running the kdray binary gave: exit status, stdout and stderr.
struct CommandResult {
    int status = -1;
    std::string out, err;
};
/// Checks kdray's promise for bad input (docs/reliability.md): exit `status` and one `kdray:
/// error:` line on stderr, ending in a newline, that mentions each of `mentions`.
void check_error(const CommandResult& r, int status, std::initializer_list<std::string> mentions);
/// The number of lines (newline characters) in `text`.
std::size_t line_count(const std::string& text);
/// Runs the kdray binary built beside the tests with `args` (no shell expansion of them). With
/// `timeout_s` > 0 a run that outlasts it is killed (status 137): a test of a hang fails, not
/// hangs. `shell_setup`, where given, is shell commands run first in the same shell (a `ulimit`,
/// an `export`): kdray inherits what they set, the test process does not.
CommandResult run_kdray(const std::vector<std::string>& args, int timeout_s = 0,
                        const std::string& shell_setup = "");
/// `text` quoted for the shell (for a shell_setup).
std::string shell_quoted(const std::string& text);

/// A fresh, empty folder for one test, under the system's temporary folder.
std::filesystem::path fresh_temp_dir(const std::string& name);

/// The bytes of `path` ("" when it cannot be read), and the file parsed as JSON.
std::string read_file(const std::filesystem::path& path);
nlohmann::json read_json(const std::filesystem::path& path);

/// Writes `text` to `path` (creating parent folders) and returns the path.
std::filesystem::path write_text_file(const std::filesystem::path& path, const std::string& text);

/// Writes the scene's triangles as an OBJ (one shape, no materials) and returns the path.
std::filesystem::path write_obj(const std::filesystem::path& path, const Scene& scene);

/// The repository root (for testdata/) and ../shared beside it (may not exist).
std::filesystem::path source_dir();

/// The first `n` frames of testdata/anim, as paths.
std::vector<std::string> anim_frames(int n);
std::filesystem::path shared_dir();

/// An environment variable set for the guard's life (this process and the kdray it runs), then
/// unset: KDRAY_PACKET_LANES, KDRAY_FORCE_NO_FP64 and the like.
struct ScopedEnv {
    ScopedEnv(const char* name, const std::string& value) : name_(name) {
        ::setenv(name, value.c_str(), 1);
    }
    ~ScopedEnv() { ::unsetenv(name_); }
    ScopedEnv(const ScopedEnv&) = delete;
    ScopedEnv& operator=(const ScopedEnv&) = delete;

  private:
    const char* name_;
};

}  // namespace kdray::test
