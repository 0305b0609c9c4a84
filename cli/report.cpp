#include "cli/report.h"

#include <spdlog/fmt/fmt.h>

#include <filesystem>
#include <iomanip>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace kdray::cli {
namespace {

void print_rows(std::ostream& out, const nlohmann::json& object, const std::string& prefix) {
    for (const auto& [key, value] : object.items()) {
        if (value.is_object()) {
            print_rows(out, value, prefix + key + ".");
            continue;
        }
        out << "  " << std::left << std::setw(34) << (prefix + key) << ' ';
        if (value.is_number_float())
            out << std::setprecision(6) << value.get<double>();
        else if (value.is_string())
            out << value.get<std::string>();
        else if (value.is_array() && value.empty())
            out << "none";
        else
            out << value.dump();
        out << '\n';
    }
}

/// `value`'s leaves under dotted keys, in the report's order ("params.tree_depth").
void flatten(const nlohmann::json& value, const std::string& prefix,
             std::vector<std::pair<std::string, nlohmann::json>>& rows) {
    for (const auto& [key, child] : value.items()) {
        // A key that names a section's own fields is flattened; a small record stays one row.
        if (child.is_object() && !child.empty() && key != "offset")
            flatten(child, prefix + key + ".", rows);
        else
            rows.emplace_back(prefix + key, child);
    }
}

bool ends_with(const std::string& s, const std::string& tail) {
    return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

bool starts_with(const std::string& s, const std::string& head) {
    return s.compare(0, head.size(), head) == 0;
}

std::string number(double v) {
    return fmt::format("{:.4g}", v);
}

/// 80356 -> "80,356 B (78.5 KiB)".
std::string bytes_text(double bytes) {
    const char* units[] = {"KiB", "MiB", "GiB", "TiB"};
    std::string exact = fmt::format("{:.0f}", bytes);
    for (int at = int(exact.size()) - 3; at > 0; at -= 3) exact.insert(std::size_t(at), ",");
    if (bytes < 1024) return exact + " B";
    double v = bytes / 1024;
    int u = 0;
    while (v >= 1024 && u < 3) {
        v /= 1024;
        ++u;
    }
    return exact + " B (" + fmt::format("{:.1f} ", v) + units[u] + ")";
}

/// A value as a reader wants it, by what its key says it is: milliseconds, bytes, a rate.
std::string value_text(const std::string& key, const nlohmann::json& v) {
    const bool ms = ends_with(key, "_ms") || key.find("timings_ms.") != std::string::npos ||
                    ends_with(key, "_ms_samples");
    if (v.is_null())
        return key.find("after_first") != std::string::npos ? "none (one frame)" : "none";
    if (v.is_boolean()) return v.get<bool>() ? "yes" : "no";
    if (v.is_string()) return v.get<std::string>();
    if (v.is_number()) {
        const double d = v.get<double>();
        if (ms) return fmt::format("{:.2f} ms", d);
        if (key.find("bytes_per_") != std::string::npos) return number(d) + " B";
        if (key.find("bytes") != std::string::npos) return bytes_text(d);
        if (key.find("per_second") != std::string::npos) return number(d) + " /s";
        if (ends_with(key, "mrays_per_s")) return number(d) + " Mrays/s";
        return v.is_number_float() ? number(d) : v.dump();
    }
    if (v.is_array()) {
        if (v.empty()) return "none";
        std::string text;
        for (const nlohmann::json& e : v) {
            if (!text.empty()) text += ", ";
            // [[size, leaves], ...]: "size:leaves".
            if (e.is_array() && e.size() == 2 && e[0].is_number() && e[1].is_number())
                text += e[0].dump() + ":" + e[1].dump();
            else if (e.is_number_float())
                text += number(e.get<double>());
            else
                text += e.is_string() ? e.get<std::string>() : e.dump();
        }
        return text + (ms ? " ms" : "");
    }
    return v.dump();
}

/// The row's label: the key without its section, its unit suffix and underscores.
std::string label_of(std::string key) {
    for (const char* section : {"scene.", "tree_file.", "render.", "combined.", "params."})
        if (starts_with(key, section)) key = key.substr(std::string(section).size());
    if (starts_with(key, "timings_ms.")) key = "build stage " + key.substr(11);
    if (ends_with(key, "_ms")) key.resize(key.size() - 3);
    for (char& c : key)
        if (c == '_') c = ' ';
    return key;
}

/// Which group a flattened key belongs to; "" for none.
std::string group_of(const std::string& key) {
    static const std::map<std::string, std::string> named = {
        {"builder", "tree"},
        {"quality", "tree"},
        {"triangles", "tree"},
        {"nodes", "tree"},
        {"inner_nodes", "tree"},
        {"leaves", "tree"},
        {"empty_leaves", "tree"},
        {"budget_leaves", "tree"},
        {"tree_depth_reached", "tree"},
        {"triangle_references", "tree"},
        {"references_per_triangle", "tree"},
        {"mean_triangles_per_leaf", "tree"},
        {"bytes", "tree"},
        {"sah_cost", "quality"},
        {"cost_traversal", "quality"},
        {"cost_intersection", "quality"},
        {"leaf_size_histogram", "quality"},
        {"leaf_depth_histogram", "quality"},
        {"small_stage", "device"},
        {"large_stage", "device"},
        {"large_node_levels", "device"},
        {"depth_first_subtrees", "device"},
        {"depth_first_rounds", "device"},
        {"depth_first_rebuilt", "device"},
        {"small_node_levels", "device"},
        {"kernel_launches", "device"},
        {"warnings", "warnings"},
    };
    if (const auto it = named.find(key); it != named.end()) return it->second;
    if (starts_with(key, "scene.")) return key == "scene.warnings" ? "warnings" : "scene";
    if (starts_with(key, "tree_file")) return "file";
    if (starts_with(key, "params.")) return "parameters";
    if (starts_with(key, "device_")) return "device";
    if (starts_with(key, "render.") || starts_with(key, "combined.")) {
        if (ends_with(key, "_ms") || key.find("per_second") != std::string::npos) return "timing";
        return "render";
    }
    if (ends_with(key, "_ms") || starts_with(key, "timings_ms.") || ends_with(key, "_ms_samples"))
        return "timing";
    return "";
}

}  // namespace

void print_table(std::ostream& out, const nlohmann::json& report) {
    for (const auto& [section, value] : report.items()) {
        out << section << '\n';
        if (value.is_object()) {
            print_rows(out, value, "");
        } else if (value.is_array() && !value.empty() && value[0].is_object()) {
            // A list of records (devices, say): one block each, numbered.
            for (std::size_t i = 0; i < value.size(); ++i)
                print_rows(out, value[i], "[" + std::to_string(i) + "].");
        } else {
            out << "  " << value.dump() << '\n';
        }
    }
}

void print_grouped(std::ostream& out, const nlohmann::json& report) {
    std::vector<std::pair<std::string, nlohmann::json>> rows;
    for (const auto& [section, value] : report.items())
        flatten(value, section == "tree" ? "" : section + ".", rows);
    const char* order[] = {"scene",  "render", "tree", "quality",  "parameters",
                           "timing", "device", "file", "warnings", "other"};
    std::map<std::string, std::vector<std::pair<std::string, std::string>>> groups;
    for (const auto& [key, value] : rows) {
        std::string group = group_of(key);
        if (group.empty()) group = "other";
        groups[group].emplace_back(label_of(key), value_text(key, value));
    }
    for (const char* group : order) {
        const auto it = groups.find(group);
        if (it == groups.end()) continue;
        out << group << '\n';
        for (const auto& [label, text] : it->second)
            out << "  " << std::left << std::setw(30) << label << ' ' << text << '\n';
    }
}

void print_frame_table(std::ostream& out, const nlohmann::json& stats) {
    const nlohmann::json& runs = stats.value("runs", nlohmann::json::array());
    auto size_of = [&](const nlohmann::json& frame) {
        const nlohmann::json* image = &stats["image"];
        if (frame.contains("run") && frame["run"].is_number_unsigned() &&
            frame["run"].get<std::size_t>() < runs.size())
            image = &runs[frame["run"].get<std::size_t>()]["image"];
        if (!image->is_object()) return std::string("?");
        return fmt::format("{}x{}", image->value("width", 0), image->value("height", 0));
    };
    out << fmt::format("{:>6}  {:<24} {:>11} {:>10} {:>10} {:>9} {:>10}\n", "frame", "input",
                       "size", "build ms", "trace ms", "nodes", "SAH");
    for (const nlohmann::json& frame : stats.value("frames", nlohmann::json::array())) {
        const nlohmann::json& tree = frame.value("tree", nlohmann::json::object());
        out << fmt::format(
            "{:>6}  {:<24} {:>11} {:>10.2f} {:>10.2f} {:>9} {:>10.4g}\n",
            frame.value("frame", std::size_t(0)),
            std::filesystem::path(frame.value("input", std::string())).filename().string(),
            size_of(frame), frame.value("build_ms", 0.0), frame.value("trace_ms", 0.0),
            tree.value("nodes", std::size_t(0)), tree.value("sah_cost", 0.0));
    }
}

}  // namespace kdray::cli
