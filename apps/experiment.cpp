// build/bin/experiment experiments/NAME.json [--out DIR] [--jobs N] [--list | --commands | --run ID | --summarize]
//
// Runs one experiment: every configuration of its sweep is polygonized (build/bin/polygonize)
// and evaluated against the cached ground truth (build/bin/evaluate), each run an independent
// job; then the per-run results are collected into summary.csv and summary.json. The format of
// the experiment file is documented in experiments/README.md.
#include "support/app_support.h"
#include "support/command_line.h"

#include <cdp/core/errors.h>
#include <cdp/io/atomic_write.h>
#include <cdp/io/field_factory.h>
#include <cdp/io/json_reader.h>
#include <cdp/io/polygonize_options.h>

#include <csignal>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>
#include <fcntl.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <mutex>
#include <shared_mutex>
#include <sstream>
#include <thread>

extern char** environ;

namespace fs = std::filesystem;

namespace {

// Exit status when the experiment ran but some of its runs failed (their rows in the tables say
// why); 1 stays "the experiment itself could not run" (a bad file, bad options).
constexpr int kSomeRunsFailed = 2;
// The most repetitions of a timed run (polygonize --repeat allows as many).
constexpr long long kMaxRepeats = 100;

struct Run {
  std::string id;
  std::string method;           // adaptive, mc, mt
  std::string parameter_name;   // factor, tolerance, chord, cell, precision
  double parameter = 0;
  std::string variant;          // adaptive: improved or paper (AdaptiveOptions::variant)
  std::string creases;          // adaptive: follow or ignore (AdaptiveOptions::creases)
  std::vector<std::string> polygonize_args;  // after FIELD -o MESH
};

struct Experiment {
  fs::path file;
  std::string name;
  std::string description;
  nlohmann::json field;        // resolved: file references relative to the output folder
  long long seed = 1;
  std::vector<Run> runs;
  int views = 6;
  int resolution = 128;
  std::string projection = "perspective";
  std::string normals;  // evaluate --normals; empty: evaluate's default (the file's)
  bool keep_meshes = true;
  int repeats = 1;  // polygonize --repeat: each run's time is the median of this many
};

std::string format_number(double v) {
  std::ostringstream s;
  s << std::setprecision(6) << v;
  return s.str();
}

// Rewrites every string of the field JSON that names an existing file relative to `from` into a
// path relative to `to`, so the written field.json works from the output folder.
void rebase_paths(nlohmann::json& j, const fs::path& from, const fs::path& to) {
  if (j.is_object() || j.is_array()) {
    for (auto& v : j) rebase_paths(v, from, to);
  } else if (j.is_string()) {
    const fs::path p = j.get<std::string>();
    std::error_code ec;
    if (p.is_relative() && !p.empty() && fs::is_regular_file(from / p, ec))
      j = fs::relative(fs::absolute(from / p), fs::absolute(to), ec).string();
  }
}

std::vector<double> numbers_or_number(cdp::JsonReader& r, const std::string& key) {
  const auto& j = r.raw(key);
  if (j.is_number()) return {j.get<double>()};
  std::vector<double> out = r.numbers(key);
  if (out.empty()) r.fail(key, "needs at least one value");
  return out;
}

Experiment read_experiment(const fs::path& file, const fs::path& out_dir) {
  Experiment e;
  e.file = file;
  e.name = file.stem().string();
  const nlohmann::json spec = cdp::read_json_file(file);
  cdp::JsonReader r(spec, file.string(), "", file.parent_path());
  r.check_keys({"description", "seed", "field", "evaluation", "keep_meshes", "repeats", "runs"});
  e.description = r.string("description", "");
  e.seed = r.integer("seed", 1);

  // The field: a file name relative to the experiment, or an inline object.
  const auto& field = r.raw("field");
  fs::path field_dir = file.parent_path();
  if (field.is_string()) {
    const fs::path field_file = r.file("field");
    e.field = cdp::read_json_file(field_file);
    field_dir = field_file.parent_path();
  } else if (field.is_object()) {
    e.field = field;
  } else {
    r.fail("field", "expected a field file name or an inline field object");
  }
  // Build it once now, so that a bad field fails here with its own message, not in every run.
  (void)cdp::make_field(e.field, field.is_string() ? (field_dir / fs::path(field.get<std::string>()).filename()).string()
                                                   : file.string() + ": field",
                        field_dir);
  rebase_paths(e.field, field_dir, out_dir);

  if (r.has("evaluation")) {
    auto ev = r.object("evaluation");
    ev.check_keys({"views", "resolution", "projection", "normals"});
    e.views = static_cast<int>(ev.integer("views", 6));
    e.resolution = static_cast<int>(ev.integer("resolution", 128));
    e.projection = ev.choice("projection", {"perspective", "orthographic"}, "perspective");
    if (e.views < 1 || e.resolution < 1) ev.fail("views and resolution must be positive");
    if (ev.has("normals")) e.normals = ev.choice("normals", {"file", "field", "mesh"}, "file");
    ev.finish({"views", "resolution", "projection", "normals"});
  }
  e.keep_meshes = r.boolean("keep_meshes", true);
  const long long repeats = r.integer("repeats", 1);
  if (repeats < 1 || repeats > kMaxRepeats) r.fail("repeats", "must be between 1 and " + std::to_string(kMaxRepeats));
  e.repeats = static_cast<int>(repeats);

  for (auto& run : r.objects("runs")) {
    const std::string method = run.choice("method", {"adaptive", "mc", "mt"});
    // The keys are the options of the polygonize program (cdp/io/polygonize_options.h, the
    // table Python's keywords come from too), its flags without their "--" and with '_' for '-'.
    std::vector<std::string> options{"method", "label"};
    for (const cdp::OptionSpec& spec : cdp::polygonize_options()) options.emplace_back(spec.name);
    run.check_keys(options);
    for (const cdp::OptionSpec& spec : cdp::polygonize_options())
      if (run.has(std::string(spec.name)) && !cdp::applies_to(spec, method))
        run.fail(std::string(spec.name), "does not apply to method \"" + method + "\"");
    std::vector<std::string> sweep_keys =
        method == "adaptive" ? std::vector<std::string>{"factor", "tolerance", "chord"} : std::vector<std::string>{"cell", "precision"};
    std::string key;
    for (const auto& k : sweep_keys)
      if (run.has(k)) {
        if (!key.empty()) run.fail(k, "give either \"" + key + "\" or \"" + k + "\", not both");
        key = k;
      }
    if (key.empty()) {
      std::string names;
      for (std::size_t i = 0; i < sweep_keys.size(); ++i)
        names += (i == 0 ? "" : i + 1 == sweep_keys.size() ? " or " : ", ") + ("\"" + sweep_keys[i] + "\"");
      run.fail("needs " + names + " (a number or a list)");
    }
    const std::vector<double> values = numbers_or_number(run, key);
    std::vector<std::string> fixed{"--method", method};
    // variant and creases are written out at their defaults too: the summary names them.
    std::string variant = method == "adaptive" ? "improved" : "", creases = method == "adaptive" ? "follow" : "";
    for (const cdp::OptionSpec& spec : cdp::polygonize_options()) {
      const std::string name(spec.name);
      if (!run.has(name) || name == key) continue;
      // evaluate, and the ground truth it caches, measure the surface F = 0.
      if (name == "level")
        run.fail("level", "experiment runs measure the surface F = 0 (their metrics take no level); write the shift "
                          "into the field instead");
      const nlohmann::json value = run.raw(name);
      try {
        cdp::polygonize_request(method, nlohmann::json{{name, value}});  // the same checks as the program's and Python's
      } catch (const cdp::InvalidInputError& e) {
        run.fail(name, e.what());
      }
      if (name == "variant") variant = value.get<std::string>();
      else if (name == "creases") creases = value.get<std::string>();
      else if (spec.kind == cdp::OptionKind::Flag) {
        if (value.get<bool>()) fixed.push_back(cdp::option_flag(spec));
      } else {
        fixed.push_back(cdp::option_flag(spec));
        fixed.push_back(value.is_string()    ? value.get<std::string>()
                        : value.is_boolean() ? std::string(value.get<bool>() ? "true" : "false")
                                             : format_number(value.get<double>()));
      }
    }
    if (method == "adaptive") fixed.insert(fixed.end(), {"--variant", variant, "--creases", creases});
    const std::string label = run.string("label", "");
    // The label becomes part of file and folder names under --out: letters, digits, '_', '-'
    // and inner dots only, so that no label can name a path elsewhere ("../x", "/tmp/x").
    constexpr std::size_t kMaxLabel = 64;
    if (label.size() > kMaxLabel || label.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-.") != std::string::npos ||
        (!label.empty() && (label.front() == '.' || label.back() == '.')) || label.find("..") != std::string::npos)
      run.fail("label", "must be at most 64 letters, digits, '_', '-' or inner '.', not \"" + label + "\"");
    run.finish(options);
    for (double v : values) {
      Run x;
      x.method = method;
      x.parameter_name = key;
      x.parameter = v;
      x.variant = variant;
      x.creases = creases;
      x.id = method + (label.empty() ? "" : "_" + label) + "_" + key + format_number(v);
      x.polygonize_args = fixed;
      x.polygonize_args.insert(x.polygonize_args.end(), {"--" + key, format_number(v)});
      for (const auto& other : e.runs)
        if (other.id == x.id) run.fail(key, "run \"" + x.id + "\" appears twice");
      e.runs.push_back(std::move(x));
    }
  }
  if (e.runs.empty()) r.fail("runs", "needs at least one run");
  r.finish({"description", "seed", "field", "evaluation", "keep_meshes", "repeats", "runs"});
  return e;
}

// Folder of this executable: the other programs are built beside it.
fs::path bin_dir() {
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  return ec ? fs::path("build/bin") : self.parent_path();
}

struct Paths {
  fs::path out, field, cache;
  fs::path mesh(const Run& r) const { return out / "meshes" / (r.id + ".ply"); }
  fs::path run_dir(const Run& r) const { return out / "runs" / r.id; }
};

std::vector<std::vector<std::string>> run_commands(const Experiment& e, const Paths& p, const Run& r) {
  std::vector<std::string> poly{(bin_dir() / "polygonize").string(), p.field.string(), "-o", p.mesh(r).string()};
  poly.insert(poly.end(), r.polygonize_args.begin(), r.polygonize_args.end());
  if (e.repeats > 1) poly.insert(poly.end(), {"--repeat", std::to_string(e.repeats)});
  poly.insert(poly.end(), {"--stats", (p.run_dir(r) / "stats.json").string()});
  std::vector<std::string> eval{(bin_dir() / "evaluate").string(),
                                p.field.string(),
                                p.mesh(r).string(),
                                "--views",
                                std::to_string(e.views),
                                "--rays",
                                std::to_string(e.resolution),
                                "--cache",
                                p.cache.string(),
                                "-o",
                                (p.run_dir(r) / "metrics.json").string()};
  if (!e.normals.empty()) eval.insert(eval.end(), {"--normals", e.normals});
  return {poly, eval};
}

std::string shell_quote(const std::string& s) {
  if (s.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-./=:,") == std::string::npos)
    return s;
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

std::string join_command(const std::vector<std::string>& argv) {
  std::string s;
  for (const auto& a : argv) s += (s.empty() ? "" : " ") + shell_quote(a);
  return s;
}

// Runs argv with stdout and stderr appended to `log`; returns the exit status (-1: not started).
int spawn_and_wait(const std::vector<std::string>& argv, const fs::path& log) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, log.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
  posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  // The child starts with no signal blocked and default handlers: it would otherwise inherit the
  // mask BlockSignals sets below, ignore the interrupt passed on to it and be killed 5 s later,
  // with its temporary output file left behind.
  posix_spawnattr_t attr;
  posix_spawnattr_init(&attr);
  sigset_t none, ours;
  sigemptyset(&none);
  sigemptyset(&ours);
  for (const int sig : {SIGINT, SIGTERM, SIGHUP}) sigaddset(&ours, sig);
  posix_spawnattr_setsigmask(&attr, &none);
  posix_spawnattr_setsigdefault(&attr, &ours);
  posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETSIGMASK | POSIX_SPAWN_SETSIGDEF);
  pid_t pid;
  int rc = 0;
  {
    // Signals wait until the child is registered, so that an interrupt reaches it too.
    cdp::app::BlockSignals block;
    rc = posix_spawn(&pid, args[0], &actions, &attr, args.data(), environ);
    if (rc == 0) cdp::app::register_child(pid);
  }
  posix_spawnattr_destroy(&attr);
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) return -1;
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  cdp::app::unregister_child(pid);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
}

std::string last_line(const fs::path& log) {
  std::ifstream in(log);
  std::string line, last;
  while (std::getline(in, line))
    if (!line.empty()) last = line;
  return last;
}

void write_json_atomically(const nlohmann::json& j, const fs::path& path) {
  cdp::write_file_atomically(path, j.dump(2) + "\n");
}

// Keeps a timed polygonization (an experiment with "repeats") from sharing the machine with the
// experiment's other steps: polygonize takes it alone, evaluations share it. The times the claims
// compare are then the method's, not the method's plus the waiting for another job's cores.
struct Timing {
  std::shared_mutex machine;
  std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();
  double since_start() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
};

// One run: polygonize, then evaluate. Its outcome goes to runs/ID/status.json, with each step's
// start and end in seconds since the experiment began (`steps`).
bool execute_run(const Experiment& e, const Paths& p, const Run& r, Timing& timing) {
  const fs::path dir = p.run_dir(r);
  fs::create_directories(dir);
  fs::create_directories(p.mesh(r).parent_path());
  const fs::path log = dir / "log.txt";
  fs::remove(log);
  nlohmann::json status{{"id", r.id}, {"status", "ok"}};
  const auto commands = run_commands(e, p, r);
  const char* steps[] = {"polygonize", "evaluate"};
  for (std::size_t i = 0; i < commands.size(); ++i) {
    { std::ofstream(log, std::ios::app) << "$ " << join_command(commands[i]) << "\n"; }
    int code = 0;
    {
      std::unique_lock<std::shared_mutex> alone(timing.machine, std::defer_lock);
      std::shared_lock<std::shared_mutex> shared(timing.machine, std::defer_lock);
      if (e.repeats > 1) {
        if (i == 0) alone.lock();
        else shared.lock();
      }
      const double begin = timing.since_start();
      code = spawn_and_wait(commands[i], log);
      status["steps"][steps[i]] = {{"start", begin}, {"end", timing.since_start()}};
    }
    if (code != 0) {
      status["status"] = "failed";
      status["reason"] = std::string(steps[i]) + " failed (exit " + std::to_string(code) + "): " + last_line(log);
      break;
    }
  }
  if (!e.keep_meshes) fs::remove(p.mesh(r));
  write_json_atomically(status, dir / "status.json");
  return status["status"] == "ok";
}

nlohmann::json read_optional(const fs::path& path) {
  std::ifstream in(path);
  if (!in) return nlohmann::json::object();
  try {
    return nlohmann::json::parse(in);
  } catch (const std::exception&) {
    return nlohmann::json::object();
  }
}

const nlohmann::json& at(const nlohmann::json& j, const std::string& pointer) {
  static const nlohmann::json null;
  const nlohmann::json::json_pointer ptr(pointer);
  return j.contains(ptr) ? j.at(ptr) : null;
}

// summary.json keeps everything per run; summary.csv the columns of the tables. Returns the
// number of runs that did not succeed (failed or not executed).
int summarize(const Experiment& e, const Paths& p) {
  static const std::vector<std::pair<std::string, std::string>> columns = {
      {"triangles", "/stats/triangles"},
      {"vertices", "/stats/vertices"},
      {"seconds", "/stats/seconds"},
      {"evaluations", "/stats/field_evaluations/total"},
      {"splits", "/stats/splits"},
      {"merges", "/stats/merges"},
      {"edge_ratio_mean", "/metrics/edge_ratio/mean"},
      {"edge_ratio_std", "/metrics/edge_ratio/std"},
      {"near_equilateral_fraction", "/metrics/near_equilateral_fraction"},
      {"min_angle_min_deg", "/metrics/min_angle_deg/min"},
      {"min_angle_mean_deg", "/metrics/min_angle_deg/mean"},
      {"depth_error_mean", "/metrics/depth_error/mean"},
      {"depth_error_std", "/metrics/depth_error/std"},
      {"depth_error_max", "/metrics/depth_error/max"},
      {"depth_error_relative_mean", "/metrics/depth_error/relative_mean"},
      {"phong_error_mean_deg", "/metrics/phong_error_deg/mean"},
      {"phong_error_std_deg", "/metrics/phong_error_deg/std"},
      {"silhouette_disagreement", "/metrics/silhouette_disagreement"},
      {"closed", "/metrics/topology/closed"},
      {"manifold", "/metrics/topology/manifold"},
      {"components", "/metrics/topology/components"},
      {"genus", "/metrics/topology/genus"},
      {"self_intersections", "/metrics/topology/self_intersections/pairs"},
      {"crease_curves", "/metrics/creases/curves"},
      {"crease_to_edges_max", "/metrics/creases/crease_to_mesh_edges/max"},
      {"crease_to_edges_mean", "/metrics/creases/crease_to_mesh_edges/mean"},
      {"edge_chamfer", "/metrics/creases/edge_chamfer"},
      {"sharp_edges", "/metrics/creases/sharp_edges"},
  };
  nlohmann::json summary{{"experiment", e.name}, {"description", e.description}, {"seed", e.seed}, {"runs", nlohmann::json::array()}};
  std::ostringstream csv;
  csv << "id,method,parameter_name,parameter,status,reason";
  for (const auto& [name, ptr] : columns) csv << "," << name;
  csv << ",triangles_per_second,evaluations_per_triangle\n";
  for (const Run& r : e.runs) {
    nlohmann::json run{{"id", r.id}, {"method", r.method}, {"parameter_name", r.parameter_name}, {"parameter", r.parameter}};
    if (!r.variant.empty()) run["variant"] = r.variant;
    if (!r.creases.empty()) run["creases"] = r.creases;
    run["stats"] = read_optional(p.run_dir(r) / "stats.json");
    run["metrics"] = read_optional(p.run_dir(r) / "metrics.json");
    const nlohmann::json status = read_optional(p.run_dir(r) / "status.json");
    std::string state = status.value("status", "missing");
    std::string reason = status.value("reason", state == "missing" ? "the run has not been executed" : "");
    // A mesh that is not closed is a failed run, reported with its reason rather than dropped.
    if (state == "ok" && at(run, "/metrics/topology/closed").is_boolean() && !at(run, "/metrics/topology/closed").get<bool>())
      state = "failed", reason = "the mesh is not closed";
    run["status"] = state;
    run["reason"] = reason;
    std::string clean_reason = reason;
    for (char& c : clean_reason)
      if (c == ',' || c == '"' || c == '\n') c = ';';
    csv << r.id << "," << r.method << "," << r.parameter_name << "," << format_number(r.parameter) << "," << state << ","
        << clean_reason;
    for (const auto& [name, ptr] : columns) {
      const auto& v = at(run, ptr);
      csv << ",";
      if (v.is_boolean()) csv << (v.get<bool>() ? "true" : "false");
      else if (v.is_number()) csv << std::setprecision(10) << v.get<double>();
    }
    const auto& tri = at(run, "/stats/triangles");
    const auto& sec = at(run, "/stats/seconds");
    const auto& ev = at(run, "/stats/field_evaluations/total");
    csv << ",";
    if (tri.is_number() && sec.is_number() && sec.get<double>() > 0) csv << tri.get<double>() / sec.get<double>();
    csv << ",";
    if (tri.is_number() && ev.is_number() && tri.get<double>() > 0) csv << ev.get<double>() / tri.get<double>();
    csv << "\n";
    summary["runs"].push_back(run);
  }
  write_json_atomically(summary, p.out / "summary.json");
  cdp::write_file_atomically(p.out / "summary.csv", csv.str(), "the summary table");
  int failed = 0;
  for (const auto& run : summary["runs"]) failed += run["status"] != "ok";
  return failed;
}

}  // namespace

int main(int argc, char** argv) {
  cdp::app::install_signal_handling();
  cdp::app::keep_freed_memory();
  try {
    CLI::App app{"Runs an experiment's sweep (experiments/README.md): every run polygonized and evaluated as an\n"
                 "independent job, then summary.csv and summary.json. Exit status 2 when some runs failed.\n",
                 "experiment"};
    cdp::app::configure(app);
    std::string file_name, out_name, run_id;
    int jobs = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
    bool list = false, commands = false, summarize_only = false;
    app.add_option("EXPERIMENT.json", file_name, "the experiment file")->required()->type_name("")->check(cdp::app::path_name());
    app.add_option("--out", out_name, "the output folder (default results/NAME)")->type_name("DIR")->check(cdp::app::path_name());
    app.add_option("--jobs", jobs, "runs at a time (default: one per core)")
        ->type_name("N")
        ->transform(cdp::app::integer_in(1, 2147483647));
    // One mode at most; each excludes the others.
    std::vector<CLI::Option*> modes{
        app.add_flag("--list", list, "print the run ids, write nothing"),
        app.add_flag("--commands", commands, "print one command per run, write nothing"),
        app.add_option("--run", run_id, "execute the run ID only")->type_name("ID")->check(cdp::app::non_empty("a run id")),
        app.add_flag("--summarize", summarize_only, "only collect the runs' results into the summary"),
    };
    for (CLI::Option* a : modes)
      for (CLI::Option* b : modes)
        if (a != b) a->excludes(b);
    if (const auto status = cdp::app::parse(app, argc, argv)) return *status;
    const fs::path file = file_name;
    fs::path out = out_name;
    const std::string mode = list ? "list" : commands ? "commands" : summarize_only ? "summarize" : !run_id.empty() ? "run" : "all";
    if (out.empty()) out = fs::path("results") / file.stem();
    const Experiment e = read_experiment(file, out);

    Paths p{out, out / "field.json", out.parent_path() / "cache"};
    // The read-only modes write nothing.
    if (mode == "list") {
      for (const auto& r : e.runs) std::cout << r.id << "\n";
      return 0;
    }
    if (mode == "commands") {
      for (const auto& r : e.runs) std::cout << join_command({argv[0], file.string(), "--out", out.string(), "--run", r.id}) << "\n";
      return 0;
    }
    const Run* only = nullptr;
    if (mode == "run") {
      for (const auto& r : e.runs)
        if (r.id == run_id) only = &r;
      if (!only) throw cdp::InvalidInputError(file.string() + ": no run \"" + run_id + "\" (see --list)");
    }
    if (mode == "summarize") {
      const int not_ok = summarize(e, p);
      if (not_ok > 0)
        std::fprintf(stderr, "experiment %s: %d of %zu runs did not succeed (see %s)\n", e.name.c_str(), not_ok,
                     e.runs.size(), (out / "summary.csv").c_str());
      return not_ok > 0 ? kSomeRunsFailed : 0;
    }
    fs::create_directories(out);
    write_json_atomically(e.field, p.field);
    Timing timing;
    if (only) return execute_run(e, p, *only, timing) ? 0 : kSomeRunsFailed;

    // Everything: the first run alone, so that it computes and caches the ground truth that all
    // runs share; then the rest in parallel (with "repeats", each polygonization alone: Timing);
    // then the summary.
    std::atomic<std::size_t> next{0};
    std::atomic<int> failed{0}, done{0};
    std::mutex print;
    const auto start = std::chrono::steady_clock::now();
    auto worker = [&](std::size_t limit) {
      for (;;) {
        std::size_t i = next.load();
        do {
          if (i >= limit) return;
        } while (!next.compare_exchange_weak(i, i + 1));
        const auto t0 = std::chrono::steady_clock::now();
        const bool ok = execute_run(e, p, e.runs[i], timing);
        failed += !ok;
        const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        std::lock_guard lock(print);
        std::fprintf(stderr, "experiment %s: [%d/%zu] %s %s (%.1f s)\n", e.name.c_str(), ++done, e.runs.size(),
                     e.runs[i].id.c_str(), ok ? "done" : "FAILED", s);
      }
    };
    worker(1);
    std::vector<std::thread> pool;
    for (int j = 0; j < std::min<int>(jobs, static_cast<int>(e.runs.size())); ++j)
      pool.emplace_back(worker, e.runs.size());
    for (auto& t : pool) t.join();
    const int not_ok = summarize(e, p);
    std::fprintf(stderr, "experiment %s: %zu runs, %d failed, %.1f s; summary in %s\n", e.name.c_str(), e.runs.size(),
                 not_ok, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(),
                 (out / "summary.csv").c_str());
    return not_ok > 0 ? kSomeRunsFailed : 0;
  } catch (const std::exception& ex) {
    std::fprintf(stderr, "experiment: %s\n", ex.what());
    return 1;
  }
}
