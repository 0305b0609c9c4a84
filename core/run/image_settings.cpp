#include "core/run/image_settings.h"

#include <algorithm>
#include <set>

#include "core/error.h"

namespace kdray {
namespace {

/// The keys of image_settings, in the order messages name them. Width and height are one
/// setting to a user: "size".
const char* const kKeys[] = {"width",    "height",  "spp",     "ray_depth", "integrator",
                             "exposure", "display", "quality", "intersect"};

std::string setting_name(const std::string& key) {
    return key == "width" || key == "height" ? "size" : key;
}

/// The settings (by setting_name) on which `a` and `b` differ, both stating them.
std::set<std::string> differences(const nlohmann::json& a, const nlohmann::json& b) {
    std::set<std::string> names;
    for (const char* key : kKeys)
        if (a.contains(key) && b.contains(key) && a[key] != b[key]) names.insert(setting_name(key));
    return names;
}

std::string value_text(const nlohmann::json& value) {
    return value.is_string() ? value.get<std::string>() : value.dump();
}

/// `settings` as a message names them, only the settings in `names`: "64x48, spp 1".
std::string describe(const nlohmann::json& settings, const std::set<std::string>& names) {
    std::string text;
    auto add = [&](const std::string& part) { text += (text.empty() ? "" : ", ") + part; };
    if (names.count("size") && settings.contains("width") && settings.contains("height"))
        add(value_text(settings["width"]) + "x" + value_text(settings["height"]));
    for (const char* key : kKeys) {
        const std::string name = setting_name(key);
        if (name == "size" || !names.count(name) || !settings.contains(key)) continue;
        add((name == "ray_depth" ? std::string("ray depth") : name) + " " +
            value_text(settings[key]));
    }
    return text;
}

/// `settings` cut to the keys of the settings in `names`: records equal there group together.
nlohmann::json projected(const nlohmann::json& settings, const std::set<std::string>& names) {
    nlohmann::json cut = nlohmann::json::object();
    for (const char* key : kKeys)
        if (names.count(setting_name(key)) && settings.contains(key)) cut[key] = settings[key];
    return cut;
}

}  // namespace

nlohmann::json image_settings(const nlohmann::json& run, const nlohmann::json& frame) {
    nlohmann::json s = nlohmann::json::object();
    if (!run.is_object()) return s;
    if (const auto image = run.find("image"); image != run.end() && image->is_object())
        for (const char* key : {"width", "height", "spp"})
            if (image->contains(key)) s[key] = (*image)[key];
    // The ray depth (the render file's max_depth), named max_depth in files before #31.
    if (run.contains("ray_depth"))
        s["ray_depth"] = run["ray_depth"];
    else if (run.contains("max_depth"))
        s["ray_depth"] = run["max_depth"];
    for (const char* key : {"integrator", "exposure", "display", "quality", "intersect"})
        if (run.contains(key)) s[key] = run[key];
    // Older files: the exposure only where --exposure set it, the quality only per frame.
    if (!s.contains("exposure") && run.contains("overrides") && run["overrides"].is_object() &&
        run["overrides"].contains("exposure"))
        s["exposure"] = run["overrides"]["exposure"];
    if (!s.contains("quality") && frame.is_object() && frame.contains("tree") &&
        frame["tree"].is_object()) {
        const nlohmann::json& tree = frame["tree"];
        if (tree.contains("quality"))
            s["quality"] = tree["quality"];
        else if (tree.value("builder", std::string()) == "reference")
            s["quality"] = "exact (reference)";
    }
    return s;
}

bool settings_differ(const nlohmann::json& a, const nlohmann::json& b) {
    return !differences(a, b).empty();
}

std::vector<nlohmann::json> record_settings(const nlohmann::json& folder) {
    std::vector<nlohmann::json> settings;
    if (!folder.is_object() || !folder.contains("frames")) return settings;
    const nlohmann::json none = nlohmann::json::object();
    const bool has_runs = folder.contains("runs") && folder["runs"].is_array();
    for (const nlohmann::json& frame : folder["frames"]) {
        const nlohmann::json* run = &folder;
        if (has_runs) {
            const std::size_t index = frame.value("run", std::size_t(0));
            run = index < folder["runs"].size() ? &folder["runs"][index] : &none;
        }
        settings.push_back(image_settings(*run, frame));
    }
    return settings;
}

void check_folder_settings(const std::string& dir, const nlohmann::json& folder,
                           const nlohmann::json& run) {
    const std::vector<nlohmann::json> records = record_settings(folder);
    std::set<std::string> names;
    for (const nlohmann::json& record : records) {
        const std::set<std::string> d = differences(record, run);
        names.insert(d.begin(), d.end());
    }
    if (names.empty()) return;
    // The differing records grouped by what they hold on the settings that differ, in the
    // order they first appear (frame order).
    std::vector<std::pair<nlohmann::json, std::size_t>> groups;
    for (const nlohmann::json& record : records) {
        if (!settings_differ(record, run)) continue;
        const nlohmann::json key = projected(record, names);
        const auto it = std::find_if(groups.begin(), groups.end(),
                                     [&](const auto& group) { return group.first == key; });
        if (it == groups.end())
            groups.emplace_back(key, 1);
        else
            ++it->second;
    }
    std::string held;
    for (const auto& [key, count] : groups)
        held += (held.empty() ? "" : " and ") + std::to_string(count) + " frame(s) " +
                (held.empty() ? "rendered " : "") + (names.count("size") ? "at " : "with ") +
                describe(key, names);
    throw UsageError(dir + " holds " + held + "; this run: " + describe(run, names) +
                     " (--overwrite replaces them, --mixed renders into a mixed folder)");
}

nlohmann::json folder_image(const nlohmann::json& merged, const nlohmann::json& newest) {
    const std::vector<nlohmann::json> records = record_settings(merged);
    // Groups of records that agree (on what both state), each with its frame numbers.
    std::vector<nlohmann::json> groups;
    for (std::size_t k = 0; k < records.size(); ++k) {
        const std::size_t number = merged["frames"][k].value("frame", std::size_t(0));
        const auto it = std::find_if(groups.begin(), groups.end(), [&](const nlohmann::json& g) {
            return !settings_differ(g, records[k]);
        });
        if (it != groups.end()) {
            (*it)["frames"].push_back(number);
            continue;
        }
        nlohmann::json group = records[k];
        group["frames"] = nlohmann::json::array({number});
        groups.push_back(std::move(group));
    }
    if (groups.size() < 2) return newest;
    std::set<std::string> names;
    for (const nlohmann::json& a : groups)
        for (const nlohmann::json& b : groups) {
            const std::set<std::string> d = differences(a, b);
            names.insert(d.begin(), d.end());
        }
    nlohmann::json image = nlohmann::json::object();
    for (const char* key : {"width", "height", "spp"})
        if (!names.count(setting_name(key)) && newest.is_object() && newest.contains(key))
            image[key] = newest[key];
    image["mixed"] = names;
    image["groups"] = groups;
    return image;
}

}  // namespace kdray
