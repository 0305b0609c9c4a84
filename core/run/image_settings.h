// image_settings.h — the settings that make a frame's image what it is (size, samples per pixel,
// ray depth, integrator, exposure, display transform, build quality, triangle test), read from
// the run settings a folder's stats.json records, and what follows from them for a folder: a run
// whose settings differ from the folder's records refuses unless told to replace them or to mix
// (--overwrite, --mixed), and a folder that holds several says so in its top-level "image".
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace kdray {

/// What a run does when the folder holds records made with other image settings.
enum class OtherSettings {
    Refuse,     // throw UsageError naming the differences, before the device opens
    Overwrite,  // drop those records (their frames in the run are rendered again)
    Mixed,      // keep them beside the run's
};

/// The image settings of a record made by `run` (a run's settings as stats.json holds them: the
/// top level or an entry of "runs"): an object of the keys width, height, spp, ray_depth,
/// integrator, exposure, display, quality, intersect that `run` states. `frame`, a frame record
/// (or null), gives the build quality where `run` does not (files written before runs stated it).
nlohmann::json image_settings(const nlohmann::json& run, const nlohmann::json& frame = nullptr);

/// Whether `a` and `b` differ on a key that both state: what an older record did not state is
/// not held against it.
bool settings_differ(const nlohmann::json& a, const nlohmann::json& b);

/// The image settings of every frame record of `folder` (a stats.json as read; null: none), in
/// its order, each from the run that made it ("run", an index into "runs"; without "runs", the
/// top level's).
std::vector<nlohmann::json> record_settings(const nlohmann::json& folder);

/// Throws UsageError when `folder` (the stats.json of `dir`) holds frame records whose image
/// settings differ from `run` (image_settings of the run about to start), naming each difference:
/// "out holds 2 frame(s) rendered at 64x48, spp 1; this run: 128x96, spp 4 (--overwrite ...)".
void check_folder_settings(const std::string& dir, const nlohmann::json& folder,
                           const nlohmann::json& run);

/// stats.json's top-level "image" for `merged` (a merged stats.json): `newest` (the newest run's
/// {width, height, spp}) when every record agrees; else, so that the file never claims one size
/// for a folder that holds several, "mixed" (the settings that differ: "size", "spp", ...) and
/// "groups" (each group's settings and "frames", its frame numbers), with width, height and spp
/// only where every record shares them.
nlohmann::json folder_image(const nlohmann::json& merged, const nlohmann::json& newest);

}  // namespace kdray
