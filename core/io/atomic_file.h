// atomic_file.h — files that appear whole or not at all: written to a temporary name beside the
// target and renamed into place, so an interrupted or failed run never leaves half a file. The one
// writer of every file kdray outputs (images, AOVs, tree files, stats.json).
#pragma once

#include <filesystem>
#include <functional>
#include <string_view>
#include <vector>

namespace kdray {

/// The temporary name for `path`: hidden, in the same folder (so the rename is atomic on one file
/// system), marked as kdray's with the host, the process id and 64 random bits, and ending in the
/// real extension so that a writer choosing the format by extension (OpenImageIO) picks the right
/// one: dir/frame.png -> dir/.frame.png.kdray.tmp@node7@123@0f3a...9c.png.
std::filesystem::path temporary_path(const std::filesystem::path& path);

/// Calls `write` with the temporary name of `path`; the file is there, empty and locked (see
/// remove_stale_temporaries), and `write` opens it by name, fills it (truncating, never replacing
/// it) and throws Error when it cannot. Then the file is renamed onto `path`. On any failure the
/// temporary file is removed and the Error propagates. A `path` that exists and is not a regular
/// file (a device node, a FIFO, a directory, a symbolic link) is refused before anything is
/// written. Names too long for the temporary suffix get a shorter, hashed temporary name.
void write_atomically(const std::filesystem::path& path,
                      const std::function<void(const std::filesystem::path& temp)>& write);

/// `bytes` as the whole content of `path`, atomically; every write and the close are checked
/// (a full disk fails here, before the rename).
void write_file_atomically(const std::filesystem::path& path, std::string_view bytes);

/// One file of write_files_atomically: where it goes and its whole content.
struct FileContent {
    std::filesystem::path path;
    std::string_view bytes;
};

/// Files that belong together (a frame's image and its AOV) written as one: every target is
/// checked as write_atomically checks it, then every file is written under its temporary name,
/// and only when all are written are they renamed into place, in the order given. A failure
/// before the renames (a full disk, a directory where one goes) leaves every target as it was.
/// A failed rename (the folder changed under the run: a target made immutable, the folder's
/// permissions) puts back the earlier files of those already renamed, kept under a second name
/// (a hard link) until every rename is done, and removes this call's files where there were
/// none; so no part of the set is left beside older files of the others, and nothing the folder
/// held is lost. Where an earlier file cannot be put back (no hard links, or the folder changed
/// again) this call's file stays in its place, never nothing, and the Error names it.
void write_files_atomically(const std::vector<FileContent>& files);

/// Removes the temporary files that a kdray process killed mid-write (SIGKILL, a power cut) left
/// in `dir`: regular files named as temporary_path names them, made on this host, that no process
/// holds locked. Every temporary is locked (flock) by its writer from its creation to its rename:
/// a lock holds across PID namespaces, where the process id in the name means nothing, and goes
/// when its holder dies. Nothing else: not a user's `.notes.tmp123`, not another host's
/// temporaries (a lock on a shared folder may be one only its node sees), and nothing on a file
/// system without locks.
void remove_stale_temporaries(const std::filesystem::path& dir);

}  // namespace kdray
