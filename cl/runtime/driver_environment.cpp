#include "cl/runtime/driver_environment.h"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <system_error>
#include <vector>

#include "core/error.h"

namespace kdray {
namespace {

namespace fs = std::filesystem;

/// The soft limit that ensure_open_file_limit raises to, at most.
constexpr rlim_t kWantedOpenFiles = 4096;

/// The vendor files through which the ICD loader finds drivers: OCL_ICD_FILENAMES (the Khronos
/// loader's and ocl-icd's list of libraries), else the *.icd files of OCL_ICD_VENDORS (a folder,
/// in place of the default) or /etc/OpenCL/vendors.
std::vector<std::string> installed_drivers() {
    std::vector<std::string> found;
    if (const char* names = std::getenv("OCL_ICD_FILENAMES"); names && *names) {
        std::string list = names;
        std::replace(list.begin(), list.end(), ';', ':');
        for (std::size_t start = 0; start <= list.size();) {
            const std::size_t end = std::min(list.find(':', start), list.size());
            if (end > start) found.push_back(list.substr(start, end - start));
            start = end + 1;
        }
        return found;
    }
    const char* vendors = std::getenv("OCL_ICD_VENDORS");
    const fs::path dir = vendors && *vendors ? fs::path(vendors) : fs::path("/etc/OpenCL/vendors");
    std::error_code ec;
    if (fs::is_regular_file(dir, ec)) return {dir.string()};
    for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec))
        if (it->path().extension() == ".icd") found.push_back(it->path().string());
    std::sort(found.begin(), found.end());
    return found;
}

std::string mib(rlim_t bytes) {
    return std::to_string(bytes >> 20) + " MiB";
}

/// What a finite memory limit says, or "" when `resource` is unlimited.
std::string memory_limit_cause(int resource, const char* name, const char* option) {
    struct rlimit limit {};
    if (::getrlimit(resource, &limit) != 0 || limit.rlim_cur == RLIM_INFINITY) return "";
    return std::string("the ") + name + " limit (`ulimit " + option + "`) is " +
           mib(limit.rlim_cur) +
           ", and OpenCL drivers reserve more address space at start than they use: raise it "
           "(`ulimit " +
           option +
           " unlimited`), or bound memory with a cgroup (memory.max), "
           "which counts what is used";
}

/// What is wrong with POCL_CACHE_DIR, where it is set and PoCL could not use it: PoCL starts no
/// device without a writable kernel cache. "" when it is unset or usable.
std::string pocl_cache_cause() {
    const char* value = std::getenv("POCL_CACHE_DIR");
    if (!value || !*value) return "";
    const fs::path dir = value;
    std::error_code ec;
    // The folder, or the nearest part of the path that exists: PoCL creates the rest.
    fs::path existing = dir;
    while (!fs::exists(existing, ec) && existing.has_relative_path() &&
           existing != existing.parent_path())
        existing = existing.parent_path();
    std::string problem;
    if (!fs::exists(existing, ec))
        return "";  // nothing of the path exists: not a path PoCL could have used either
    if (!fs::is_directory(existing, ec))
        problem = "is not a folder";
    else if (::access(existing.c_str(), W_OK | X_OK) != 0)
        problem = "is not writable";
    else
        return "";
    std::string cause = "POCL_CACHE_DIR is '" + dir.string() + "', which ";
    if (existing == dir) {
        cause += problem;
    } else {
        cause += "cannot be made: ";
        cause += existing.string();
        cause += ' ';
        cause += problem;
    }
    cause +=
        "; PoCL starts no device without a writable kernel cache: point it at a writable "
        "folder, or unset it";
    return cause;
}

}  // namespace

void ensure_open_file_limit() {
    struct rlimit limit {};
    if (::getrlimit(RLIMIT_NOFILE, &limit) != 0) return;
    const rlim_t wanted = std::min(limit.rlim_max, kWantedOpenFiles);
    if (limit.rlim_cur < wanted) {
        struct rlimit raised = limit;
        raised.rlim_cur = wanted;
        if (::setrlimit(RLIMIT_NOFILE, &raised) == 0) limit = raised;
    }
    if (limit.rlim_cur >= kMinOpenFiles) return;
    throw Error("this process may have only " + std::to_string(limit.rlim_cur) +
                " files open at once (`ulimit -n`; its hard limit is " +
                (limit.rlim_max == RLIM_INFINITY ? std::string("unlimited")
                                                 : std::to_string(limit.rlim_max)) +
                "), fewer than the " + std::to_string(kMinOpenFiles) +
                " an OpenCL driver needs to compile kdray's kernels: raise it (`ulimit -n 1024`)");
}

std::string no_device_message(const std::string& failure) {
    const std::vector<std::string> drivers = installed_drivers();
    if (drivers.empty())
        return failure +
               ". Install an OpenCL implementation, e.g. PoCL for the CPU: "
               "`apt-get install pocl-opencl-icd ocl-icd-opencl-dev`, or your GPU vendor's driver";
    std::string listed;
    for (const std::string& d : drivers) {
        if (!listed.empty()) listed += ", ";
        listed += d;
    }
    std::vector<std::string> causes;
    for (const std::string& cause :
         {memory_limit_cause(RLIMIT_AS, "address-space", "-v"),
          memory_limit_cause(RLIMIT_DATA, "data-segment", "-d"), pocl_cache_cause()})
        if (!cause.empty()) causes.push_back(cause);
    std::string message = failure + ", though " + std::to_string(drivers.size()) +
                          " OpenCL driver" + (drivers.size() == 1 ? " is" : "s are") +
                          " installed (" + listed + "), so none could start here";
    if (causes.empty())
        return message +
               ": with ocl-icd, `OCL_ICD_DEBUG=15` shows what the loader tried, and `clinfo` "
               "what the drivers report";
    message += "; likely why: ";
    for (std::size_t i = 0; i < causes.size(); ++i) {
        if (i > 0) message += "; and ";
        message += causes[i];
    }
    return message;
}

}  // namespace kdray
