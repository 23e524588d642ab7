// Writing a file so that a failure never leaves a half-written one: the contents go to a hidden
// temporary file beside the target, which is then renamed over it. Every program's output goes
// through here (meshes through mesh_io, which does the same around OpenMesh's writer).
#pragma once

#include <filesystem>
#include <string_view>

namespace cdp {

// Throws InvalidInputError "PATH: cannot write[ WHAT][: reason]", leaving neither the target
// changed nor the temporary file behind.
void write_file_atomically(const std::filesystem::path& path, std::string_view contents, std::string_view what = {});

}  // namespace cdp
