// Sampled volumes from files, for the "volume" field type (cdp/core/models/volume.h):
// numpy's .npy (a 3-D array of any real or integer type, C or Fortran order) and NRRD (.nrrd,
// the format of 3D Slicer and ITK: raw or gzip encoding, data attached, an axis-aligned space).
#pragma once

#include <cdp/core/models/volume.h>

#include <filesystem>

namespace cdp {

// The samples of a volume file, by extension. An .npy file has no geometry: origin 0, spacing 1
// (the caller places it); an NRRD file's "space origin" and "space directions" (or "spacings")
// give them.
// \throw FileError "PATH: cannot read volume: reason" for a file that cannot be opened or read.
// \throw InvalidInputError "PATH: problem" for another extension, a malformed or truncated
//        file, an array that is not 3-D, an unsupported type or encoding, a space that is not
//        axis-aligned, or an NRRD file whose data lies in another file.
VolumeSamples read_volume(const std::filesystem::path& path);

}  // namespace cdp
