// driver_environment.h — what the process's environment must give an OpenCL driver, checked
// before kdray opens a device, and why an installed driver did not start when none did. Without
// it an exhausted limit read as a missing driver: `ulimit -v 600000`, `ulimit -n 5` or a
// POCL_CACHE_DIR through a file each said "Install an OpenCL implementation", and `ulimit -n 10`
// with a cold kernel cache made PoCL abort (its linker ran out of descriptors).
#pragma once

#include <cstdint>
#include <string>

namespace kdray {

/// The fewest files a process of kdray's may have open at once to use an OpenCL device. PoCL
/// compiling kdray's kernels on a CPU device needs more than 12 (measured: `kdray render` with
/// a cold cache fails at `ulimit -n 12`, runs at 16); GPU drivers open a descriptor per device
/// node and per queue on top. 64 leaves room for both.
inline constexpr std::uint64_t kMinOpenFiles = 64;

/// Raises the soft limit on open files to the hard limit, up to 4096 (the usual practice: the
/// soft limit is often 1024 or less while the hard one allows more; not beyond 4096, since a
/// program that closes every descriptor up to the limit before exec, as some build tools that
/// drivers run do, slows down with a hard limit of 2^20). Throws Error, naming the limits and
/// the remedy, when even the hard limit is below kMinOpenFiles.
void ensure_open_file_limit();

/// The message for "no OpenCL device started": `failure` (what failed, with the OpenCL error)
/// followed by what to do. Where no driver is installed (no vendor file for the ICD loader), how
/// to install one; where one is, the installed drivers and what in the environment most likely
/// stopped them: an address-space or data limit (`ulimit -v`, `ulimit -d`), a POCL_CACHE_DIR
/// that cannot be a writable folder, else how to see what the ICD loader tried.
std::string no_device_message(const std::string& failure);

}  // namespace kdray
