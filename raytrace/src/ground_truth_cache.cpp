#include <cdp/raytrace/ground_truth_cache.h>

#include <cdp/core/errors.h>
#include <cdp/io/atomic_write.h>

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <type_traits>

namespace cdp {

namespace {

// Bump when the ray caster or the file layout changes: old cache files then stop matching.
constexpr int kFormatVersion = 1;
constexpr char kMagic[8] = {'C', 'D', 'P', 'G', 'T', 'v', '0', '1'};

std::uint64_t fnv1a64(const std::string& text) {
  std::uint64_t h = 0xcbf29ce484222325ull;
  for (unsigned char c : text) {
    h ^= c;
    h *= 0x100000001b3ull;
  }
  return h;
}

nlohmann::json raycast_json(const RaycastOptions& o) {
  return {{"lipschitz", o.lipschitz},         {"lipschitz_grid", o.lipschitz_grid},
          {"lipschitz_safety", o.lipschitz_safety}, {"min_step", o.min_step},
          {"tangent_tolerance", o.tangent_tolerance}, {"max_steps", o.max_steps},
          {"max_refine_iterations", o.max_refine_iterations}};
}

// Fixed-size little-endian-as-stored PODs; the files are a cache for this machine kind.
class Writer {
 public:
  explicit Writer(std::string& out) : out_(out) {}
  template <class T>
  void put(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    out_.append(reinterpret_cast<const char*>(&v), sizeof(T));
  }
  void put_bytes(const char* p, std::size_t n) { out_.append(p, n); }
  void put_vec(const Vec3& v) {
    put(v.x());
    put(v.y());
    put(v.z());
  }

 private:
  std::string& out_;
};

class Reader {
 public:
  Reader(std::ifstream& in, std::string name) : in_(in), name_(std::move(name)) {}
  template <class T>
  T get() {
    T v;
    in_.read(reinterpret_cast<char*>(&v), sizeof(T));
    if (!in_) fail("truncated");
    return v;
  }
  Vec3 get_vec() {
    const double x = get<double>(), y = get<double>(), z = get<double>();
    return {x, y, z};
  }
  [[noreturn]] void fail(const std::string& what) const {
    throw InvalidInputError(name_ + ": not a usable ground-truth cache file (" + what + "); delete it to recompute");
  }

 private:
  std::ifstream& in_;
  std::string name_;
};

}  // namespace

std::string ground_truth_key(const std::string& field_json_text, const CameraOptions& camera,
                             const RaycastOptions& raycast) {
  nlohmann::json field;
  try {
    field = nlohmann::json::parse(field_json_text);
  } catch (const nlohmann::json::exception& e) {
    throw InvalidInputError(std::string("ground truth key: the field is not valid JSON: ") + e.what());
  }
  // nlohmann::json keeps object keys sorted, so dump() is canonical.
  const nlohmann::json all{{"version", kFormatVersion}, {"field", field}, {"camera", to_json(camera)},
                           {"raycast", raycast_json(raycast)}};
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(fnv1a64(all.dump())));
  return buf;
}

std::filesystem::path ground_truth_path(const std::filesystem::path& dir, const std::string& key) {
  return dir / ("gt_" + key + ".bin");
}

void save_ground_truth(const GroundTruth& truth, const std::filesystem::path& dir, const std::string& key) {
  if (truth.rays.size() != truth.hits.size()) throw InvalidInputError("save_ground_truth: rays and hits differ in number");
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw InvalidInputError(dir.string() + ": cannot create the cache folder: " + ec.message());
  const auto path = ground_truth_path(dir, key);
  std::string bytes;
  Writer w(bytes);
  w.put_bytes(kMagic, sizeof kMagic);
  w.put(static_cast<std::uint32_t>(key.size()));
  w.put_bytes(key.data(), key.size());
  const RaycastSetup& s = truth.setup;
  w.put_vec(s.box.min);
  w.put_vec(s.box.max);
  w.put(s.lipschitz);
  w.put(static_cast<std::uint8_t>(s.lipschitz_from_model));
  w.put(s.min_step);
  w.put(s.tangent_tolerance);
  w.put(static_cast<std::uint64_t>(truth.rays.size()));
  for (std::size_t i = 0; i < truth.rays.size(); ++i) {
    const Ray& r = truth.rays[i];
    const SurfaceHit& h = truth.hits[i];
    w.put_vec(r.origin);
    w.put_vec(r.direction);
    w.put(static_cast<std::uint8_t>(h.status));
    w.put(h.flags);
    w.put(h.steps);
    w.put(h.t);
    w.put_vec(h.normal);
  }
  w.put_bytes(kMagic, sizeof kMagic);  // end marker: a complete file ends with it
  write_file_atomically(path, bytes, "the ground-truth cache");
}

std::optional<GroundTruth> load_ground_truth(const std::filesystem::path& dir, const std::string& key) {
  const auto path = ground_truth_path(dir, key);
  if (!std::filesystem::exists(path)) return std::nullopt;
  std::ifstream in(path, std::ios::binary);
  Reader r(in, path.string());
  if (!in) r.fail("cannot open");
  char magic[sizeof kMagic];
  in.read(magic, sizeof magic);
  if (!in || std::memcmp(magic, kMagic, sizeof kMagic) != 0) r.fail("wrong magic or version");
  const auto key_size = r.get<std::uint32_t>();
  if (key_size > 1024) r.fail("bad key");
  std::string stored(key_size, '\0');
  in.read(stored.data(), key_size);
  if (!in || stored != key) r.fail("key mismatch");
  GroundTruth t;
  t.setup.box.min = r.get_vec();
  t.setup.box.max = r.get_vec();
  t.setup.lipschitz = r.get<double>();
  t.setup.lipschitz_from_model = r.get<std::uint8_t>() != 0;
  t.setup.min_step = r.get<double>();
  t.setup.tangent_tolerance = r.get<double>();
  const auto n = r.get<std::uint64_t>();
  const auto size = std::filesystem::file_size(path);
  constexpr std::uint64_t kPerRay = 6 * 8 + 1 + 1 + 4 + 8 + 3 * 8;
  if (n > size / kPerRay) r.fail("ray count larger than the file");
  t.rays.resize(n);
  t.hits.resize(n);
  for (std::uint64_t i = 0; i < n; ++i) {
    t.rays[i].origin = r.get_vec();
    t.rays[i].direction = r.get_vec();
    const auto status = r.get<std::uint8_t>();
    if (status > static_cast<std::uint8_t>(RayStatus::NotFinite)) r.fail("bad ray status");
    t.hits[i].status = static_cast<RayStatus>(status);
    t.hits[i].flags = r.get<std::uint8_t>();
    t.hits[i].steps = r.get<std::int32_t>();
    t.hits[i].t = r.get<double>();
    t.hits[i].normal = r.get_vec();
  }
  in.read(magic, sizeof magic);
  if (!in || std::memcmp(magic, kMagic, sizeof kMagic) != 0) r.fail("missing end marker");
  if (in.peek() != std::char_traits<char>::eof()) r.fail("trailing bytes");
  return t;
}

GroundTruth cached_ground_truth(const Field& field, std::vector<Ray> rays, const RaycastOptions& raycast,
                                const std::filesystem::path& dir, const std::string& key, bool* cached,
                                const std::function<void()>& before_casting) {
  if (!dir.empty()) {
    std::optional<GroundTruth> truth = load_ground_truth(dir, key);
    const auto same_rays = [&](const std::vector<Ray>& stored) {
      if (stored.size() != rays.size()) return false;
      for (std::size_t i = 0; i < rays.size(); ++i)
        if (stored[i].origin != rays[i].origin || stored[i].direction != rays[i].direction) return false;
      return true;
    };
    if (truth && same_rays(truth->rays)) {
      if (cached) *cached = true;
      return std::move(*truth);
    }
  }
  if (cached) *cached = false;
  if (before_casting) before_casting();
  GroundTruth truth = compute_ground_truth(field, std::move(rays), raycast);
  if (!dir.empty()) save_ground_truth(truth, dir, key);
  return truth;
}

}  // namespace cdp
