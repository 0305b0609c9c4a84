#include "cli/report.h"

#include <iomanip>
#include <ostream>
#include <string>

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

}  // namespace kdray::cli
