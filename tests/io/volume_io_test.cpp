// Volume files (io/include/cdp/io/volume_io.h): .npy and NRRD give the samples they hold, in the
// order and place they say; every truncation of a file and every malformed header is an error
// naming the file, never a crash, another exception or a read past the bytes (this test runs
// under the sanitizers).
#include <gtest/gtest.h>

#include <cdp/core/errors.h>
#include <cdp/io/volume_io.h>

#include <cstring>
#include <fstream>
#include <string>

#include "common/run_command.h"

namespace cdp {
namespace {

std::string npy(const std::string& descr, bool fortran, const std::string& shape, const std::string& data) {
  std::string header = "{'descr': '" + descr + "', 'fortran_order': " + (fortran ? "True" : "False") +
                       ", 'shape': (" + shape + "), }";
  header.append(63 - (10 + header.size()) % 64, ' ');
  header += '\n';
  std::string out("\x93NUMPY\x01\x00", 8);
  out += static_cast<char>(header.size() & 0xff);
  out += static_cast<char>(header.size() >> 8);
  return out + header + data;
}

template <class T>
std::string bytes_of(const std::vector<T>& v) {
  return std::string(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
}

std::filesystem::path write(const test::TempDir& dir, const std::string& name, const std::string& bytes) {
  std::ofstream(dir.path / name, std::ios::binary) << bytes;
  return dir.path / name;
}

TEST(VolumeFiles, NpyInEitherOrderAndNrrdGiveTheirSamples) {
  test::TempDir dir("volume_files");
  std::vector<double> c(2 * 3 * 4);
  for (std::size_t f = 0; f < c.size(); ++f) c[f] = static_cast<double>(f) * 0.5 - 3;
  const VolumeSamples a = read_volume(write(dir, "c.npy", npy("<f8", false, "2, 3, 4", bytes_of(c))));
  EXPECT_EQ(a.dims, (std::array<std::size_t, 3>{2, 3, 4}));
  EXPECT_EQ(a.values, c);
  EXPECT_EQ(a.origin, Vec3::Zero());
  EXPECT_EQ(a.spacing, Vec3::Ones());
  // The same array stored in Fortran order as int16: sample (i, j, k) at (k * 3 + j) * 2 + i.
  std::vector<std::int16_t> f(c.size());
  for (std::size_t i = 0; i < 2; ++i)
    for (std::size_t j = 0; j < 3; ++j)
      for (std::size_t k = 0; k < 4; ++k) f[(k * 3 + j) * 2 + i] = static_cast<std::int16_t>(2 * c[(i * 3 + j) * 4 + k]);
  const VolumeSamples b = read_volume(write(dir, "f.npy", npy("<i2", true, "2, 3, 4", bytes_of(f))));
  for (std::size_t n = 0; n < c.size(); ++n) EXPECT_EQ(b.values[n], 2 * c[n]);
  // NRRD: the first axis fastest, with its spacing and origin; a negative direction flips its axis.
  const std::string header = "NRRD0004\ntype: short\ndimension: 3\nsizes: 2 3 4\nencoding: raw\nendian: little\n"
                             "space origin: (1,2,3)\n";
  const VolumeSamples n = read_volume(write(
      dir, "v.nrrd", header + "space directions: (0.5,0,0) (0,2,0) (0,0,-1)\n\n" + bytes_of(f)));
  EXPECT_EQ(n.spacing, Vec3(0.5, 2, 1));
  EXPECT_EQ(n.origin, Vec3(1, 2, 0));
  for (std::size_t i = 0; i < 2; ++i)
    for (std::size_t j = 0; j < 3; ++j)
      for (std::size_t k = 0; k < 4; ++k) EXPECT_EQ(n.values[(i * 3 + j) * 4 + k], 2 * c[(i * 3 + j) * 4 + (3 - k)]);
}

TEST(VolumeFiles, EveryTruncationAndMalformedHeaderIsAnErrorNamingTheFile) {
  test::TempDir dir("volume_files_bad");
  std::vector<float> v(4 * 4 * 4, 1.0f);
  const std::string good_npy = npy("<f4", false, "4, 4, 4", bytes_of(v));
  const std::string good_nrrd = "NRRD0004\ntype: float\ndimension: 3\nsizes: 4 4 4\nencoding: raw\n\n" + bytes_of(v);
  ASSERT_NO_THROW(read_volume(write(dir, "ok.npy", good_npy)));
  ASSERT_NO_THROW(read_volume(write(dir, "ok.nrrd", good_nrrd)));
  // 60,000 blanks in the shape's tuple: still a tuple, read in one pass.
  EXPECT_EQ(read_volume(write(dir, "spaces.npy", npy("<f4", false, std::string(60000, ' ') + "4, 4, 4", bytes_of(v)))).dims,
            (std::array<std::size_t, 3>{4, 4, 4}));
  for (const auto& [name, good] : {std::pair{std::string("cut.npy"), good_npy}, std::pair{std::string("cut.nrrd"), good_nrrd}})
    for (std::size_t length = 0; length < good.size(); ++length) {
      const auto path = write(dir, name, good.substr(0, length));
      EXPECT_THROW(read_volume(path), InvalidInputError) << name << " cut to " << length << " bytes";
    }
  const std::vector<std::pair<std::string, std::string>> bad = {
      {"two_d.npy", npy("<f4", false, "16, 4", bytes_of(v))},
      {"complex.npy", npy("<c8", false, "4, 4, 2", bytes_of(v))},
      {"half.npy", npy("<f2", false, "4, 4, 8", bytes_of(v))},
      {"zero.npy", npy("<f4", false, "0, 4, 4", "")},
      {"huge.npy", npy("<f4", false, "100000, 100000, 100000", bytes_of(v))},
      {"version.npy", "\x93NUMPY\x09\x00" + good_npy.substr(8)},
      {"skew.nrrd", "NRRD0004\ntype: float\ndimension: 3\nsizes: 4 4 4\nencoding: raw\n"
                    "space directions: (1,0.5,0) (0,1,0) (0,0,1)\n\n" + bytes_of(v)},
      {"detached.nrrd", "NRRD0004\ntype: float\ndimension: 3\nsizes: 4 4 4\nencoding: raw\ndata file: x.raw\n\n"},
      {"ascii.nrrd", "NRRD0004\ntype: float\ndimension: 3\nsizes: 4 4 4\nencoding: ascii\n\n1 2 3"},
      {"gzip.nrrd", "NRRD0004\ntype: float\ndimension: 3\nsizes: 4 4 4\nencoding: gzip\n\nnot gzip at all"},
      {"type.nrrd", "NRRD0004\ntype: block\ndimension: 3\nsizes: 4 4 4\nencoding: raw\n\n" + bytes_of(v)},
      {"four_d.nrrd", "NRRD0004\ntype: float\ndimension: 4\nsizes: 4 4 4 1\nencoding: raw\n\n" + bytes_of(v)},
      {"volume.vti", "<VTKFile/>"},
      // Headers made to hurt a parser: long runs (a regex recursed on them until the stack
      // overflowed), numbers beyond every type, sizes that are not whole numbers.
      {"wide_type.npy", npy("<f99999999999999999999", false, "4, 4, 4", bytes_of(v))},
      {"wide_shape.npy", npy("<f4", false, "99999999999999999999999, 4, 4", bytes_of(v))},
      {"digits.nrrd", "NRRD0004\ntype: float\ndimension: 3\nsizes: " + std::string(300000, '4') +
                          " 4 4\nencoding: raw\n\n" + bytes_of(v)},
      {"nan_size.nrrd", "NRRD0004\ntype: float\ndimension: 3\nsizes: nan 4 4\nencoding: raw\n\n" + bytes_of(v)},
      {"huge_size.nrrd", "NRRD0004\ntype: float\ndimension: 3\nsizes: 1e30 4 4\nencoding: raw\n\n" + bytes_of(v)},
      {"inf_spacing.nrrd", "NRRD0004\ntype: float\ndimension: 3\nsizes: 4 4 4\nspacings: 1e999 1 1\n"
                           "encoding: raw\n\n" + bytes_of(v)},
      {"long_header.nrrd", "NRRD0004\n# " + std::string(2 << 20, 'x') + "\ntype: float\n\n"},
  };
  for (const auto& [name, bytes] : bad) {
    const auto path = write(dir, name, bytes);
    try {
      read_volume(path);
      ADD_FAILURE() << name << " was read";
    } catch (const InvalidInputError& e) {
      const std::string what = e.what();
      EXPECT_EQ(what.rfind(path.string() + ": ", 0), 0u) << what;
      EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    }
  }
  EXPECT_THROW(read_volume(dir.path / "missing.npy"), FileError);
}

}  // namespace
}  // namespace cdp
