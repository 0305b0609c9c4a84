// test_hostile_round3_environment.cpp — issue #29, problem 17: an environment that stops the
// OpenCL driver (a limit on open files or on address space, an unusable POCL_CACHE_DIR) is named
// for what it is, not reported as a missing driver ("Install an OpenCL implementation"), and a
// low soft limit on open files is raised rather than left to abort PoCL mid-compile. Each runs
// the binary under the environment, set by its shell only.
#include <doctest/doctest.h>
#include <sys/resource.h>

#include <filesystem>
#include <string>

#include "tests/support.h"

namespace fs = std::filesystem;
using namespace kdray::test;

namespace {

// A build that compiles kdray's kernels with a cold cache takes seconds; a hang must still fail.
constexpr int kNoHang = 120;

/// Shell commands that leave PoCL the ICD loader's only driver (a copy of its vendor file in a
/// folder of its own): the cases below are PoCL's, and a machine with a GPU driver beside it
/// would otherwise start that one. "" when PoCL is not installed.
std::string pocl_only(const fs::path& dir) {
    const fs::path vendor = "/etc/OpenCL/vendors/pocl.icd";
    std::error_code ec;
    if (!fs::is_regular_file(vendor, ec)) return "";
    fs::create_directories(dir / "vendors");
    fs::copy_file(vendor, dir / "vendors" / "pocl.icd", ec);
    if (ec) return "";
    return "export OCL_ICD_VENDORS=" + shell_quoted((dir / "vendors").string()) +
           "; export POCL_CACHE_DIR=" + shell_quoted((dir / "pocl-cache").string());
}

fs::path triangle(const fs::path& dir) {
    return write_text_file(dir / "tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
}

void check_not_install_advice(const CommandResult& r) {
    CHECK_MESSAGE(r.err.find("Install an OpenCL") == std::string::npos, r.err);
}

}  // namespace

TEST_CASE("a hard limit of 5 open files is refused with the limit, before the driver starts") {
    // `ulimit -n 5` (soft and hard) said "Install an OpenCL implementation", and `ulimit -n 10`
    // with a cold kernel cache made PoCL's linker run out of descriptors: exit 134.
    const fs::path dir = fresh_temp_dir("round3-nofile");
    const fs::path obj = triangle(dir);
    // Descriptors 3 and 4 closed first, as in a user's shell: a test runner may pass its own
    // down (CI's did), and with them open the sanitizer build's UBSan could not make the pipe(2)
    // it probes memory with, and reported every virtual call before kdray said a word.
    const CommandResult r =
        run_kdray({"build", obj.string()}, kNoHang, "exec 3>&- 4>&-; ulimit -n 5");
    check_error(r, 1, {"ulimit -n", "only 5 files", "64"});
    check_not_install_advice(r);
    fs::remove_all(dir);
}

TEST_CASE("a soft limit of 10 open files is raised to the hard limit: a cold build succeeds") {
    // Only the soft limit is low (`ulimit -Sn 10`): kdray raises it, as most programs that open
    // many files do, and builds with a cold kernel cache (a fresh POCL_CACHE_DIR), which at 10
    // descriptors aborted PoCL. The one triangle's tree is a single leaf.
    const fs::path dir = fresh_temp_dir("round3-nofile-soft");
    const std::string setup = pocl_only(dir);
    struct rlimit limit {};
    if (setup.empty() || ::getrlimit(RLIMIT_NOFILE, &limit) != 0 || limit.rlim_max < 64) {
        MESSAGE("skipped: PoCL is not installed, or this process's hard limit is below 64");
        fs::remove_all(dir);
        return;
    }
    const fs::path obj = triangle(dir);
    const CommandResult r =
        run_kdray({"build", obj.string(), "--json"}, kNoHang, setup + "; ulimit -Sn 10");
    INFO("stderr: " << r.err);
    REQUIRE(r.status == 0);
    const nlohmann::json tree = nlohmann::json::parse(r.out);
    CHECK(tree["triangles"] == 1);
    CHECK(tree["leaves"] == 1);
    fs::remove_all(dir);
}

TEST_CASE("a POCL_CACHE_DIR through a file is named, not a missing driver") {
    // PoCL starts no device when it cannot make its kernel cache: "platforms exist but have no
    // devices. Install an OpenCL implementation" sent the user to reinstall a working driver.
    const fs::path dir = fresh_temp_dir("round3-pocl-cache");
    const std::string setup = pocl_only(dir);
    if (setup.empty()) {
        MESSAGE("skipped: PoCL is not installed");
        fs::remove_all(dir);
        return;
    }
    const fs::path file = write_text_file(dir / "a-file", "not a folder\n");
    const fs::path obj = triangle(dir);
    const CommandResult r =
        run_kdray({"build", obj.string()}, kNoHang,
                  setup + "; export POCL_CACHE_DIR=" + shell_quoted((file / "cache").string()));
    check_error(r, 1, {"POCL_CACHE_DIR", file.string() + " is not a folder", "pocl.icd"});
    check_not_install_advice(r);
    fs::remove_all(dir);
}

TEST_CASE("an address-space limit that stops the driver is named with its size") {
#ifdef KDRAY_SANITIZE
    MESSAGE("skipped: AddressSanitizer reserves terabytes of address space at start");
#else
    // `ulimit -v 600000` (585 MiB): PoCL reserves more than that at start, and the ICD loader
    // says "no platform", which read as "Install an OpenCL implementation".
    const fs::path dir = fresh_temp_dir("round3-address-space");
    const std::string setup = pocl_only(dir);
    if (setup.empty()) {
        MESSAGE("skipped: PoCL is not installed");
        fs::remove_all(dir);
        return;
    }
    const fs::path obj = triangle(dir);
    const CommandResult r =
        run_kdray({"build", obj.string()}, kNoHang, setup + "; ulimit -v 600000");
    check_error(r, 1, {"ulimit -v", "585 MiB", "pocl.icd"});
    check_not_install_advice(r);
    fs::remove_all(dir);
#endif
}
