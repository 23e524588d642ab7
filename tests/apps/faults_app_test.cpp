// The programs under faults and bad input (issue 13): a full disk, signals, outputs that would
// replace inputs, malformed files and options, and the messages for each. Every case ends with
// one line "program: ..." and exit status 1 (or death by the signal sent), no partial output, no
// temporary file left behind, and nothing overwritten.
#include <gtest/gtest.h>

#include <cdp/core/mesh_topology.h>
#include <cdp/io/mesh_io.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <thread>

#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include "apps/app_files.h"
#include "common/run_command.h"
#include "support/app_support.h"

namespace cdp {
namespace {

namespace fs = std::filesystem;

using test::kTorus;
constexpr const char* kSphere = R"({"type": "sphere", "radius": 1})";

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// Files whose name starts with '.', anywhere below dir: the temporaries of interrupted writes.
std::vector<std::string> hidden_files(const fs::path& dir) {
  std::vector<std::string> out;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.path().filename().string().front() == '.') out.push_back(e.path().string());
  return out;
}

void expect_one_line_error(const test::CommandResult& r, const std::string& program, const std::string& expected,
                           const std::string& context) {
  EXPECT_EQ(r.exit_code, 1) << context << "\n" << r.err;
  EXPECT_EQ(r.err.rfind(program + ": ", 0), 0u) << context << "\n" << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << context << "\n" << r.err;
  EXPECT_NE(r.err.find(expected), std::string::npos) << context << "\n" << r.err;
}

// ---- 1. Full disk ----------------------------------------------------------------------------

TEST(Faults, AFileSizeLimitIsAWriteErrorWithNoFileLeft) {
  // A file size limit makes write() fail with EFBIG exactly as a full disk fails with ENOSPC,
  // and needs no privileges: every format and the stats must report it.
  test::TempDir dir("faults_fsize");
  const auto field = dir.write("torus.json", kTorus);
  for (const char* ext : {"ply", "obj", "off"}) {
    const fs::path out = dir.path / (std::string("out.") + ext);
    // 8 blocks of 1 KiB: far less than the mesh of a torus at factor 3.
    const auto r = test::run_shell("ulimit -f 8; exec " + test::bin("polygonize") + " " + field.string() + " -o " +
                                   out.string() + " --factor 3");
    expect_one_line_error(r, "polygonize", "File too large", ext);
    EXPECT_FALSE(fs::exists(out)) << ext;
    EXPECT_TRUE(hidden_files(dir.path).empty()) << ext;
  }
}

TEST(Faults, AFullTmpfsIsAWriteErrorWithNoFileLeft) {
  // The real thing where the machine allows it (root with mount namespaces, as on CI): a 64 KiB
  // tmpfs mounted in a private namespace, which disappears with the command.
  if (geteuid() != 0 || test::run_shell("unshare -m true").exit_code != 0)
    GTEST_SKIP() << "needs root and unshare -m (the file size limit test covers the same path)";
  test::TempDir dir("faults_tmpfs");
  const auto field = dir.write("torus.json", kTorus);
  const fs::path mnt = dir.path / "small";
  fs::create_directories(mnt);
  for (const char* ext : {"ply", "obj", "off"}) {
    const std::string out = (mnt / (std::string("out.") + ext)).string();
    const auto r = test::run_shell("unshare -m sh -c 'mount -t tmpfs -o size=64k tmpfs " + mnt.string() + " && " +
                                   test::bin("polygonize") + " " + field.string() + " -o " + out +
                                   " --factor 3; status=$?; ls -A " + mnt.string() + "; exit $status'");
    expect_one_line_error(r, "polygonize", "No space left on device", ext);
    EXPECT_EQ(r.out, "") << "files left on the full disk: " << r.out;
  }
}

// ---- 5. Precision ----------------------------------------------------------------------------

TEST(Faults, MeshesFarFromTheOriginAndTinyMeshesKeepTheirTriangles) {
  test::TempDir dir("faults_precision");
  const auto far = dir.write("far.json", R"({"type": "torus", "center": [1e6, 0, 0], "major_radius": 1,
                                             "minor_radius": 0.35, "bounds": [[999998, -2, -1], [1000002, 2, 1]]})");
  const auto tiny = dir.write("tiny.json", R"({"type": "sphere", "radius": 1e-6,
                                              "bounds": [[-2e-6, -2e-6, -2e-6], [2e-6, 2e-6, 2e-6]]})");
  for (const auto& field : {far, tiny})
    for (const char* ext : {"ply", "obj", "off"}) {
      const fs::path out = dir.path / (field.stem().string() + "." + ext), stats = dir.path / "stats.json";
      const auto r = test::run_app("polygonize", field.string() + " -o " + out.string() + " --factor 2 --stats " + stats.string());
      ASSERT_EQ(r.exit_code, 0) << r.err;
      const Mesh m = read_mesh(out);
      EXPECT_TRUE(analyze_topology(m).closed()) << out;
      // Every vertex distinct and every triangle of positive area, as computed.
      std::vector<Vec3> sorted = m.positions;
      std::sort(sorted.begin(), sorted.end(), [](const Vec3& a, const Vec3& b) {
        return std::tie(a.x(), a.y(), a.z()) < std::tie(b.x(), b.y(), b.z());
      });
      EXPECT_EQ(std::adjacent_find(sorted.begin(), sorted.end()), sorted.end()) << out;
      double min_angle = 180;
      for (const auto& t : m.triangles) {
        const Vec3 u = m.positions[t[1]] - m.positions[t[0]], v = m.positions[t[2]] - m.positions[t[0]];
        ASSERT_GT(u.cross(v).norm(), 0) << out;
        for (int k = 0; k < 3; ++k) {
          const Vec3& p = m.positions[t[k]];
          const Vec3 a = m.positions[t[(k + 1) % 3]] - p, b = m.positions[t[(k + 2) % 3]] - p;
          min_angle = std::min(min_angle, std::atan2(a.cross(b).norm(), a.dot(b)) * 180 / M_PI);
        }
      }
      // The stats describe the file: the smallest angle of the written triangles is the one reported.
      std::ifstream in(stats);
      const auto j = nlohmann::json::parse(in);
      EXPECT_NEAR(j["min_angle_degrees"].get<double>(), min_angle, 1e-9) << out;
    }
}

// ---- 10. Bounded runs ------------------------------------------------------------------------
// The neighbour searches' bound is tested with the library's option for it
// (AdaptiveOptions::max_search_visits, polygonizer/adaptive/polygonizer_test.cpp). The run that ended by it
// here, a thin torus beside a sphere at factor 3 with --min-edge 1e-4, meshes since the vertex
// hash splits crowded cells (polygonizer/adaptive/hard_surfaces_test.cpp, AdaptiveScales).

// ---- 12. Outputs that coincide ---------------------------------------------------------------

TEST(Faults, OutputsThatCoincideWithEachOtherOrWithAnInputAreErrors) {
  test::TempDir dir("faults_paths");
  const auto field = dir.write("torus.json", kTorus);
  const fs::path mesh = dir.path / "mesh.ply";
  ASSERT_EQ(test::run_app("polygonize", field.string() + " -o " + mesh.string() + " --factor 1").exit_code, 0);
  const std::string mesh_bytes = slurp(mesh), field_bytes = slurp(field);
  fs::create_directories(dir.path / "sub");
  fs::create_directories(dir.path / "folder.ply");
  const fs::path same_mesh = dir.path / "sub" / ".." / "mesh.ply";  // the same file by another name
  fs::create_directories(dir.path / "locked");
  fs::permissions(dir.path / "locked", fs::perms::owner_read | fs::perms::owner_exec);
  struct Case {
    std::string program, args, expected;
  };
  const std::vector<Case> cases = {
      {"polygonize", field.string() + " -o " + (dir.path / "x.ply").string() + " --stats " + (dir.path / "x.ply").string(),
       "given both to -o and to --stats"},
      {"polygonize", field.string() + " -o " + same_mesh.string() + " --stats " + mesh.string(), "given both"},
      {"polygonize", field.string() + " -o " + (dir.path / "torus.json").string(), "the extension must be"},
      {"polygonize", field.string() + " -o " + (dir.path / "y.ply").string() + " --stats " + field.string(),
       "overwrite an input"},
      {"polygonize", field.string() + " -o " + (dir.path / "y.ply").string() + " --stats " +
                         (dir.path / "nowhere" / "s.json").string(), "does not exist"},
      {"polygonize", field.string() + " -o " + (dir.path / "folder.ply").string(), "is a folder"},
      {"evaluate", field.string() + " " + mesh.string() + " -o " + mesh.string(), "overwrite an input"},
      {"evaluate", field.string() + " " + mesh.string() + " -o " + field.string(), "overwrite an input"},
      {"render", mesh.string() + " -o " + (dir.path / "sub" / "p.png").string() + " -o " + (dir.path / "q.png").string(),
       "-o given twice"},
  };
  for (const auto& c : cases) {
    const auto r = test::run_app(c.program, c.args);
    expect_one_line_error(r, c.program, c.expected, c.args);
  }
  EXPECT_EQ(slurp(mesh), mesh_bytes);
  EXPECT_EQ(slurp(field), field_bytes);
  EXPECT_FALSE(fs::exists(dir.path / "x.ply"));
  EXPECT_FALSE(fs::exists(dir.path / "y.ply"));
  // An unwritable --stats folder is found before the mesh is made (and so before it is written).
  if (geteuid() != 0) {  // root writes anywhere
    const auto r = test::run_app("polygonize", field.string() + " -o " + (dir.path / "z.ply").string() + " --stats " +
                                                   (dir.path / "locked" / "s.json").string());
    expect_one_line_error(r, "polygonize", "cannot write in", "locked");
    EXPECT_FALSE(fs::exists(dir.path / "z.ply"));
  }
  fs::permissions(dir.path / "locked", fs::perms::owner_all);
}

// ---- 13. Signals -----------------------------------------------------------------------------

struct Child {
  pid_t pid = -1;
  int err_fd = -1;  // the read end of its standard error
};

Child start(const std::vector<std::string>& argv) {
  int fds[2];
  if (pipe(fds) != 0) return {};
  const pid_t pid = fork();
  if (pid == 0) {
    dup2(fds[1], STDERR_FILENO);
    close(fds[0]);
    close(fds[1]);
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    execv(args[0], args.data());
    _exit(127);
  }
  close(fds[1]);
  return {pid, fds[0]};
}

// Reads the child's stderr until a line holding `text` (true) or its end (false).
bool wait_for_line(const Child& c, const std::string& text, std::string& seen) {
  char buf[256];
  for (;;) {  // bounded by the child's output, which ends when it exits
    const ssize_t n = read(c.err_fd, buf, sizeof buf);
    if (n <= 0) return false;
    seen.append(buf, static_cast<std::size_t>(n));
    if (seen.find(text) != std::string::npos) return true;
  }
}

// Runs `argv`, sends `sig` once its stderr shows a line holding `line`, and returns its wait
// status (a test failure, and -1, when it ends before that line).
int signal_after_line(const std::vector<std::string>& argv, const std::string& line, int sig) {
  const Child c = start(argv);
  EXPECT_GT(c.pid, 0);
  if (c.pid <= 0) return -1;
  std::string seen;
  const bool reached = wait_for_line(c, line, seen);
  EXPECT_TRUE(reached) << seen;
  if (reached) kill(c.pid, sig);
  int status = 0;
  waitpid(c.pid, &status, 0);
  close(c.err_fd);
  return reached ? status : -1;
}

TEST(Faults, ASignalDuringTheWriteLeavesNoTemporaryAndEndsTheProgramByThatSignal) {
  test::TempDir dir("faults_signal");
  const auto field = dir.write("sphere.json", kSphere);
  for (const int sig : {SIGINT, SIGTERM}) {
    const fs::path out = dir.path / "big.ply";
    // About 800k triangles: a write of some 40 MB, long enough to be interrupted in the middle.
    const int status = signal_after_line({test::bin("polygonize"), field.string(), "-o", out.string(), "--method", "mc",
                                          "--cell", "0.007", "--progress"},
                                         "writing", sig);
    EXPECT_TRUE(hidden_files(dir.path).empty()) << strsignal(sig);
    if (WIFSIGNALED(status)) {
      EXPECT_EQ(WTERMSIG(status), sig);
      EXPECT_FALSE(fs::exists(out)) << "the rename happens after the write";
    } else {
      // The write finished before the signal arrived: then the file is whole.
      EXPECT_EQ(WEXITSTATUS(status), 0);
      EXPECT_GT(read_mesh(out).num_triangles(), 0u);
    }
    fs::remove(out);
  }
}

TEST(Faults, ASignalDuringACancellableRunCancelsItsTokenAndEndsTheProgramAfterTheRun) {
  // The programs' handler in a child process of its own: the first signal during a run only
  // cancels the run's token (the run goes on to its next poll), and the program ends by that
  // signal when the run is over.
  test::TempDir dir("faults_cancellable_run");
  const fs::path marker = dir.path / "after_the_signal";
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    cdp::app::install_signal_handling();
    {
      const cdp::app::CancellableRun run;
      raise(SIGINT);
      if (!cdp::app::run_token().cancelled()) _exit(3);
      std::ofstream(marker) << "the run went on to its next poll\n";
    }  // the program ends here, by SIGINT
    _exit(4);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGINT) << status;
  EXPECT_TRUE(fs::exists(marker));
}

TEST(Faults, ASignalWhileTheAdaptiveMethodMeshesEndsTheProgramByThatSignalWithNothingWritten) {
  test::TempDir dir("faults_signal_meshing");
  const auto field = dir.write("torus.json", R"({"type": "torus", "major_radius": 1, "minor_radius": 0.3})");
  for (const int sig : {SIGINT, SIGTERM}) {
    const fs::path out = dir.path / "torus.ply", stats = dir.path / "stats.json";
    // Factor 60: seconds of tracking, long enough to be interrupted while it meshes.
    const int status = signal_after_line({test::bin("polygonize"), field.string(), "-o", out.string(), "--factor", "60",
                                          "--stats", stats.string(), "--progress"},
                                         "meshing", sig);
    EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == sig) << strsignal(sig) << " " << status;
    EXPECT_FALSE(fs::exists(out));
    EXPECT_FALSE(fs::exists(stats));
    EXPECT_TRUE(hidden_files(dir.path).empty()) << strsignal(sig);
  }
}

bool process_alive(pid_t pid) {
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  if (!stat) return false;
  std::string line;
  std::getline(stat, line);
  // "pid (comm) S ...": a zombie (Z) or dead (X) process has ended.
  const auto close_paren = line.rfind(')');
  return close_paren != std::string::npos && close_paren + 2 < line.size() && line[close_paren + 2] != 'Z' &&
         line[close_paren + 2] != 'X';
}

// The signals a process blocks, from the SigBlk line of /proc/PID/status (bit n-1 is signal n).
unsigned long long blocked_signals(pid_t pid) {
  std::ifstream status("/proc/" + std::to_string(pid) + "/status");
  std::string line;
  while (std::getline(status, line))
    if (line.rfind("SigBlk:", 0) == 0) return std::stoull(line.substr(7), nullptr, 16);
  return 0;
}

std::string command_name(pid_t pid) {
  std::ifstream comm("/proc/" + std::to_string(pid) + "/comm");
  std::string name;
  std::getline(comm, name);
  return name;
}

unsigned long long interrupt_bits() {
  unsigned long long bits = 0;
  for (const int sig : {SIGINT, SIGTERM, SIGHUP}) bits |= 1ull << (sig - 1);
  return bits;
}

std::vector<pid_t> children_of(pid_t parent) {
  std::vector<pid_t> out;
  for (const auto& e : fs::directory_iterator("/proc")) {
    const std::string name = e.path().filename().string();
    if (name.find_first_not_of("0123456789") != std::string::npos) continue;
    std::ifstream stat(e.path() / "stat");
    std::string line;
    std::getline(stat, line);
    const auto close_paren = line.rfind(')');
    if (close_paren == std::string::npos) continue;
    std::istringstream rest(line.substr(close_paren + 2));
    char state;
    pid_t ppid = 0;
    rest >> state >> ppid;
    if (ppid == parent) out.push_back(std::stoi(name));
  }
  return out;
}

TEST(Faults, InterruptingAnExperimentStopsItsChildren) {
  test::TempDir dir("faults_experiment_signal");
  dir.write("sphere.json", kSphere);
  const auto exp = dir.write("slow.json", R"({"field": "sphere.json",
    "runs": [{"method": "mc", "cell": [0.005, 0.0051, 0.0052, 0.0053]}]})");
  const Child c = start({test::bin("experiment"), exp.string(), "--out", (dir.path / "out").string(), "--jobs", "2"});
  ASSERT_GT(c.pid, 0);
  std::vector<pid_t> kids;
  for (int i = 0; i < 200 && kids.empty(); ++i) {  // up to 20 s for the first polygonize to start
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    kids = children_of(c.pid);
  }
  ASSERT_FALSE(kids.empty()) << "experiment started no child";
  // The children must be able to receive the interrupt passed on to them (a child that inherits
  // the parent's blocked signals ignores it and is killed 5 s later with its temporary file left).
  // (Read once the child runs polygonize: between the spawn and the exec the mask is the parent's.)
  for (const pid_t k : kids) {
    for (int i = 0; i < 100 && process_alive(k) && command_name(k) != "polygonize"; ++i)
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    if (command_name(k) == "polygonize") {
      EXPECT_EQ(blocked_signals(k) & interrupt_bits(), 0u) << "child " << k;
    }
  }
  kill(c.pid, SIGINT);
  int status = 0;
  waitpid(c.pid, &status, 0);
  close(c.err_fd);
  EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGINT) << status;
  for (int i = 0; i < 50; ++i) {  // the children end within 5 s
    bool any = false;
    for (const pid_t k : kids) any = any || process_alive(k);
    if (!any) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  for (const pid_t k : kids) EXPECT_FALSE(process_alive(k)) << "child " << k << " still running";
  EXPECT_TRUE(hidden_files(dir.path).empty());
}

// ---- 14-16. Messages and options -------------------------------------------------------------

TEST(Faults, BadFilesAndOptionsGetPreciseOneLineMessages) {
  test::TempDir dir("faults_messages");
  const auto torus = dir.write("torus.json", kTorus);
  const auto huge = dir.write("huge.json", R"({"type": "sphere", "radius": 1e999})");
  const auto twice = dir.write("twice.json", R"({"type": "sphere", "radius": 1, "radius": 2})");
  const auto inverted = dir.write("inverted.json", R"({"type": "expression", "value": "1-x^2-y^2-z^2",
                                                      "bounds": [[-2,-2,-2],[2,2,2]]})");
  const auto mesh = dir.path / "mesh.ply";
  ASSERT_EQ(test::run_app("polygonize", torus.string() + " -o " + mesh.string() + " --factor 1").exit_code, 0);
  // A PLY whose header claims far more vertices than the file holds.
  std::string ply = slurp(mesh);
  const auto at = ply.find("element vertex ");
  ply.replace(at, ply.find('\n', at) - at, "element vertex 2000000000");
  const auto lying = dir.write("lying.ply", ply);
  const auto garbage_obj = dir.write("garbage.obj", "this is not a mesh\n");
  const auto header_only = dir.write("header.ply", "ply\nformat ascii 1.0\nend_header\n");
  fs::create_directories(dir.path / "folder.json");
  fs::create_directories(dir.path / "folder.ply");
  const std::string out = (dir.path / "out.ply").string(), metrics = (dir.path / "m.json").string();
  struct Case {
    std::string program, args, expected;
  };
  const std::vector<Case> cases = {
      {"polygonize", (dir.path / "folder.json").string() + " -o " + out, "folder.json: is a folder"},
      {"polygonize", huge.string() + " -o " + out, "huge.json: malformed JSON: number overflow"},
      {"polygonize", twice.string() + " -o " + out, "twice.json: the key \"radius\" appears twice"},
      {"polygonize", inverted.string() + " -o " + out, "inverted.json: seeding: F < 0 on the whole boundary"},
      {"polygonize", inverted.string() + " -o " + out + " --method mc", "looks inverted"},
      {"polygonize", torus.string() + " -o " + out + " --seed-resolution 1000000", "use a resolution of at most"},
      {"polygonize", torus.string() + " -o " + out + " --seed-resolution 2147483648", "between 2 and 2147483647"},
      {"polygonize", torus.string() + " -o " + out + " --method mc --cell 0", "--cell: expects a positive number, found \"0\""},
      {"polygonize", torus.string() + " -o " + out + " --method mt --precision 6", "--precision: expects an integer between 0 and 5, found \"6\""},
      {"polygonize", torus.string() + " -o " + out + " -o " + out, "--output given twice"},
      {"polygonize", torus.string() + " -o " + out + " --factor 3 --max-triangles 20", torus.string() + ": adaptive:"},
      {"evaluate", torus.string() + " " + lying.string() + " -o " + metrics, "too short"},
      {"evaluate", torus.string() + " " + garbage_obj.string() + " -o " + metrics, "garbage.obj:1: unknown OBJ statement"},
      {"evaluate", torus.string() + " " + header_only.string() + " -o " + metrics, "header.ply: the mesh has no triangles"},
      {"evaluate", torus.string() + " " + (dir.path / "folder.ply").string() + " -o " + metrics, "is a directory"},
      {"evaluate", torus.string() + " " + mesh.string() + " -o " + metrics + " --samples 0", "--samples"},
      {"evaluate", (dir.path / "folder.json").string() + " " + mesh.string() + " -o " + metrics, "is a folder"},
      {"render", lying.string() + " -o " + (dir.path / "p.png").string(), "too short"},
  };
  for (const auto& c : cases) {
    const auto r = test::run_app(c.program, c.args);
    expect_one_line_error(r, c.program, c.expected, c.args);
    EXPECT_FALSE(fs::exists(out)) << c.args;
    EXPECT_FALSE(fs::exists(metrics)) << c.args;
  }
}

TEST(Faults, SuccessfulWritesPrintNothingOfTheMeshLibrary) {
  // OpenMesh logs "[OBJWriter] : write file" on every OBJ it writes; the programs say nothing on
  // success unless asked.
  test::TempDir dir("faults_quiet");
  const auto torus = dir.write("torus.json", kTorus);
  for (const char* ext : {"ply", "obj", "off"}) {
    const auto r = test::run_app("polygonize", torus.string() + " -o " + (dir.path / (std::string("t.") + ext)).string());
    EXPECT_EQ(r.exit_code, 0);
    EXPECT_EQ(r.err, "") << ext;
    EXPECT_EQ(r.out, "") << ext;
  }
}

// ---- 17. Progress ----------------------------------------------------------------------------

TEST(Faults, ProgressLinesNameEveryPhaseForLogs) {
  test::TempDir dir("faults_progress");
  const auto torus = dir.write("torus.json", kTorus);
  const auto out = dir.path / "t.ply";
  const auto r = test::run_app("polygonize", torus.string() + " -o " + out.string() + " --progress");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const char* phase : {"reading the field", "sampling the seed grid", "meshing", "checking the mesh", "writing "})
    EXPECT_NE(r.err.find(std::string("polygonize: adaptive torus.json: ") + phase), std::string::npos) << phase << "\n" << r.err;
  EXPECT_EQ(r.err.find('\r'), std::string::npos) << "no bar in a log";
  const auto e = test::run_app("evaluate", torus.string() + " " + out.string() + " -o " + (dir.path / "m.json").string() +
                                               " --rays 32 --views 2 --progress");
  ASSERT_EQ(e.exit_code, 0) << e.err;
  for (const char* phase : {"reading the field and the mesh", "casting rays", "measuring the mesh", "writing "})
    EXPECT_NE(e.err.find(phase), std::string::npos) << phase << "\n" << e.err;
  const auto both = test::run_app("polygonize", torus.string() + " -o " + out.string() + " --progress --quiet");
  expect_one_line_error(both, "polygonize", "--quiet excludes --progress", "both");
}

}  // namespace
}  // namespace cdp
