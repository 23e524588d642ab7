// Ground truth on disk: computed once per model and camera set, reused by every mesh of it.
// This file (and its .cpp) is the only place of the module that touches the file system.
#pragma once

#include <cdp/raytrace/camera.h>
#include <cdp/raytrace/implicit_raycast.h>

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace cdp {

// 16 hex digits: FNV-1a 64 of the field's JSON (parsed and re-serialized, so formatting and key
// order do not matter), the camera options, the ray-casting options and a format version.
// Files the JSON refers to (point clouds) are identified by name only: change their name when
// their content changes. Throws InvalidInputError when field_json_text is not JSON.
// \throw InvalidInputError when field_json_text is not JSON.
std::string ground_truth_key(const std::string& field_json_text, const CameraOptions& camera,
                             const RaycastOptions& raycast);

// <dir>/gt_<key>.bin
std::filesystem::path ground_truth_path(const std::filesystem::path& dir, const std::string& key);

// Writes a temporary file and renames it, creating `dir` if needed. Throws InvalidInputError on
// an I/O failure.
// \throw InvalidInputError when truth.rays and truth.hits differ in number, or `dir` cannot be
//        created.
// \throw FileError (an InvalidInputError) when the file cannot be written (write_file_atomically).
void save_ground_truth(const GroundTruth& truth, const std::filesystem::path& dir, const std::string& key);

// Empty when there is no file for the key; throws InvalidInputError naming the file when it
// exists but is not a complete ground truth of this format and key.
// \return the stored rays, hits and setup.
// \throw InvalidInputError "FILE: not a usable ground-truth cache file (problem); ..." for a file that
//        cannot be opened, is truncated or has trailing bytes, or whose magic, key, ray count, ray
//        status or end marker is wrong.
// \throw std::filesystem::filesystem_error when the file's status or size cannot be read.
std::optional<GroundTruth> load_ground_truth(const std::filesystem::path& dir, const std::string& key);

// The ground truth of `field` along `rays`: read from `dir` when it holds one for `key` cast
// along the same rays (a file written by a build whose rays differ is stale and is cast again),
// otherwise cast now (`before_casting` is called first) and, when `dir` is not empty, saved
// there. `cached` (optional) tells which. The one cache policy of evaluate and the benchmarks.
// \pre as compute_ground_truth.
// \throw as load_ground_truth (a stored file that is not usable is an error: it is not cast again),
//        compute_ground_truth and save_ground_truth; what before_casting throws.
GroundTruth cached_ground_truth(const Field& field, std::vector<Ray> rays, const RaycastOptions& raycast,
                                const std::filesystem::path& dir, const std::string& key, bool* cached = nullptr,
                                const std::function<void()>& before_casting = {});

}  // namespace cdp
