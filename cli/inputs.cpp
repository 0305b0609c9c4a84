#include "cli/inputs.h"

#include <glob.h>

#include <algorithm>
#include <filesystem>

#include "core/error.h"
#include "core/io/natural_order.h"

namespace kdray::cli {

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
    // Sorted, duplicates kept: a path given twice keeps the frame numbers of its positions, and
    // render refuses the two writers of one image by name (check_output_names).
    std::stable_sort(files.begin(), files.end(), natural_less);
    return files;
}

}  // namespace kdray::cli
