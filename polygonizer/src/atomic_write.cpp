#include <polygonizer/atomic_write.h>
#include <polygonizer/errors.h>

#include <fstream>
#include <string>

#include <unistd.h>

namespace cdp {

void write_file_atomically(const std::filesystem::path& path, std::string_view contents, std::string_view what) {
  const std::string failure = path.string() + ": cannot write" + (what.empty() ? "" : " " + std::string(what));
  std::filesystem::path tmp = path;
  // Hidden and per process, so that concurrent writers of one target never share a temporary.
  tmp.replace_filename("." + path.filename().string() + ".tmp" + std::to_string(getpid()));
  std::error_code ec;
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    out.write(contents.data(), static_cast<std::streamsize>(contents.size()));
    out.close();
    if (!out) {
      std::filesystem::remove(tmp, ec);
      throw InvalidInputError(failure);
    }
  }
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    const std::string reason = ec.message();
    std::filesystem::remove(tmp, ec);
    throw InvalidInputError(failure + ": " + reason);
  }
}

}  // namespace cdp
