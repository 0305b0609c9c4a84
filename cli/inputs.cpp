#include "cli/inputs.h"

#include <glob.h>

#include <algorithm>
#include <cctype>
#include <filesystem>

#include "core/error.h"

namespace kdray::cli {

bool natural_less(const std::string& a, const std::string& b) {
    std::size_t i = 0, j = 0;
    while (i < a.size() && j < b.size()) {
        if (std::isdigit(static_cast<unsigned char>(a[i])) &&
            std::isdigit(static_cast<unsigned char>(b[j]))) {
            // Compare digit runs by value: skip leading zeros, then longer is larger.
            std::size_t i0 = i, j0 = j;
            while (i < a.size() && std::isdigit(static_cast<unsigned char>(a[i]))) ++i;
            while (j < b.size() && std::isdigit(static_cast<unsigned char>(b[j]))) ++j;
            std::string_view da(a.data() + i0, i - i0), db(b.data() + j0, j - j0);
            while (da.size() > 1 && da.front() == '0') da.remove_prefix(1);
            while (db.size() > 1 && db.front() == '0') db.remove_prefix(1);
            if (da.size() != db.size()) return da.size() < db.size();
            if (da != db) return da < db;
            continue;
        }
        if (a[i] != b[j]) return a[i] < b[j];
        ++i, ++j;
    }
    if ((a.size() - i) != (b.size() - j)) return (a.size() - i) < (b.size() - j);
    return a < b;  // equal under natural order ("1" vs "01"): any fixed order
}

std::vector<std::string> expand_inputs(const std::vector<std::string>& arguments) {
    std::vector<std::string> files;
    for (const std::string& arg : arguments) {
        if (std::filesystem::exists(arg)) {
            if (std::filesystem::is_directory(arg))
                throw Error(arg + ": is a folder, not an OBJ file");
            files.push_back(arg);
            continue;
        }
        if (arg.find_first_of("*?[") == std::string::npos) throw Error(arg + ": no such file");
        glob_t matches{};
        int status = ::glob(arg.c_str(), 0, nullptr, &matches);
        if (status == 0)
            for (std::size_t k = 0; k < matches.gl_pathc; ++k)
                files.emplace_back(matches.gl_pathv[k]);
        ::globfree(&matches);
        if (status != 0) throw Error(arg + ": no file matches this pattern");
    }
    std::sort(files.begin(), files.end(), natural_less);
    files.erase(std::unique(files.begin(), files.end()), files.end());
    return files;
}

}  // namespace kdray::cli
