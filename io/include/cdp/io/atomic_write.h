// Writing a file so that a failure never leaves a half-written one: the contents go to a hidden
// temporary file beside the target, are flushed to the disk, and the temporary is then renamed
// over the target. Every program's output goes through here (meshes, statistics, metrics, ground
// truth caches, pictures, experiment tables).
#pragma once

#include <filesystem>
#include <functional>
#include <string_view>

namespace cdp {

// Throws InvalidInputError "PATH: cannot write[ WHAT]: reason" (reason from errno: "No space
// left on device", "File too large", "Permission denied", ...), leaving neither the target
// changed nor the temporary file behind.
// \throw FileError (an InvalidInputError, errno in error_number()) when the temporary file cannot be
//        created, written, flushed or closed, or cannot be renamed over the target.
void write_file_atomically(const std::filesystem::path& path, std::string_view contents, std::string_view what = {});

// The same with the contents made in pieces, so that a large file (a mesh of 10^7 triangles is
// hundreds of megabytes) is never held whole: `produce` is called once with `append`, which
// writes each piece it is given to the temporary file, in order. An exception from `produce`
// removes the temporary and goes on unchanged.
// \throw FileError as above; what `produce` throws.
using ByteSink = std::function<void(std::string_view)>;
void write_file_atomically(const std::filesystem::path& path, const std::function<void(const ByteSink& append)>& produce,
                           std::string_view what = {});

// For a signal handler: removes the temporary file a write in progress has open, if any. Only
// async-signal-safe calls (unlink), so that an interrupted program leaves nothing hidden behind.
void remove_pending_temporary_file() noexcept;

}  // namespace cdp
