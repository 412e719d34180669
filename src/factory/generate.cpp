#include "hypershape/factory/generate.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <petscsys.h>
#include <sys/resource.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <csignal>
#include <filesystem>
#include <regex>
#include <sstream>
#include <thread>

#include "hypershape/config/scene.hpp"
#include "hypershape/core/collective.hpp"
#include "hypershape/core/error.hpp"
#include "hypershape/core/log.hpp"
#include "hypershape/core/timer.hpp"
#include "hypershape/core/interrupt.hpp"
#include "hypershape/factory/dataset_index.hpp"
#include "hypershape/factory/output_lock.hpp"
#include "hypershape/factory/preflight.hpp"
#include "hypershape/factory/shard_record.hpp"
#include "hypershape/factory/shape_job.hpp"
#include "hypershape/factory/shape_pipeline.hpp"
#include "hypershape/factory/shape_set.hpp"
#include "hypershape/io/dataset_shard.hpp"
#include "hypershape/mesh/gmsh_mesher.hpp"
#include "hypershape/solver/nonlinear.hpp"
#include "text_file.hpp"

namespace hypershape::factory {

namespace fs = std::filesystem;

std::string shard_name(std::int64_t k) { return fmt::format("shard-{:06d}.h5", k); }

using detail::read_text;
using detail::write_atomically;

namespace {

/// Counters on rank 0, updated by one-sided atomics from the group roots.
enum Counter { next_shard = 0, shapes_done, loads_ok, loads_failed, shapes_failed, n_counters };

class SharedCounters {
 public:
  explicit SharedCounters(MPI_Comm comm) {
    MPI_Comm_rank(comm, &rank_);
    const MPI_Aint bytes = rank_ == 0 ? MPI_Aint(n_counters * sizeof(std::int64_t)) : 0;
    MPI_Win_allocate(bytes, sizeof(std::int64_t), MPI_INFO_NULL, comm, &base_, &win_);
    if (rank_ == 0) {
      MPI_Win_lock(MPI_LOCK_EXCLUSIVE, 0, 0, win_);
      for (int i = 0; i < n_counters; ++i) base_[i] = 0;
      MPI_Win_unlock(0, win_);
    }
    MPI_Barrier(comm);
  }
  ~SharedCounters() { MPI_Win_free(&win_); }
  std::int64_t fetch_add(Counter c, std::int64_t v) {
    std::int64_t old = 0;
    MPI_Win_lock(MPI_LOCK_SHARED, 0, 0, win_);
    MPI_Fetch_and_op(&v, &old, MPI_INT64_T, 0, MPI_Aint(c), MPI_SUM, win_);
    MPI_Win_unlock(0, win_);
    return old;
  }
  std::array<std::int64_t, n_counters> read() {
    std::array<std::int64_t, n_counters> out{};
    for (int i = 0; i < n_counters; ++i) out[std::size_t(i)] = fetch_add(Counter(i), 0);
    return out;
  }

 private:
  int rank_ = 0;
  std::int64_t* base_ = nullptr;
  MPI_Win win_;
};

double peak_rss_mib() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_maxrss) / 1024.0;
}

std::map<std::string, std::string> software_versions() {
  char petsc[256];
  PetscGetVersion(petsc, sizeof petsc);
  return {{"petsc", petsc}, {"gmsh", mesh::gmsh_version()}};
}

/// What rank 0 found and holds in the output directory.
struct OutputState {
  std::unique_ptr<OutputLock> lock;  ///< rank 0 only
  std::string text, hash;            ///< dataset.yaml's text (stored in shards), the identity
  std::vector<std::int64_t> todo;
  std::int64_t done_before = 0;
};

void broadcast_text(MPI_Comm comm, std::string& s) {
  int n = int(s.size());
  MPI_Bcast(&n, 1, MPI_INT, 0, comm);
  s.resize(std::size_t(n));
  MPI_Bcast(s.data(), n, MPI_CHAR, 0, comm);
}

/// Everything but the lock, from rank 0 to all. Collective.
void broadcast_output(MPI_Comm comm, OutputState& st) {
  broadcast_text(comm, st.text);
  broadcast_text(comm, st.hash);
  std::int64_t n = std::int64_t(st.todo.size());
  MPI_Bcast(&n, 1, MPI_INT64_T, 0, comm);
  st.todo.resize(std::size_t(n));
  MPI_Bcast(st.todo.data(), int(n), MPI_INT64_T, 0, comm);
  MPI_Bcast(&st.done_before, 1, MPI_INT64_T, 0, comm);
}

/// The first line where two canonical texts differ, for the "another dataset" message.
std::string first_difference(const std::string& a, const std::string& b) {
  std::istringstream sa(a), sb(b);
  std::string la, lb, section;  // section: the last unindented line ("shapes:"), for nested keys
  while (true) {
    const bool ga = bool(std::getline(sa, la)), gb = bool(std::getline(sb, lb));
    if (!ga && !gb) return "";
    const auto at = [&](const std::string& l) { return l.rfind("  ", 0) == 0 ? section + " " + l.substr(2) : l; };
    if (la != lb || ga != gb) return fmt::format("'{}' there, '{}' here", ga ? at(la) : "", gb ? at(lb) : "");
    if (!la.empty() && la[0] != ' ') section = la;
  }
}

bool any_shard(const fs::path& out) {
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(out / "shards", ec))
    if (e.path().extension() == ".h5") return true;
  return false;
}

/// The text stored with the data: the existing dataset.yaml when it holds this dataset (the
/// same meaning, whatever its layout), else this config's (nothing there yet, or what a start
/// on a full disk left: an empty dataset.yaml and no shard). Throws InputError for another
/// dataset or a dataset.yaml that is not a config. Reads only.
std::string dataset_text(const config::DatasetConfig& cfg, const fs::path& out) {
  const fs::path yaml = out / "dataset.yaml";
  std::error_code ec;
  if (!fs::exists(yaml, ec)) return cfg.text;
  const std::string there = read_text(yaml);
  // An empty dataset.yaml and no shard: what a start on a full disk left (before writes were
  // checked): nothing to protect.
  if (there.find_first_not_of(" \t\r\n") == std::string::npos && !any_shard(out)) return cfg.text;
  std::string meaning;
  try {
    meaning = config::canonical_text(config::parse_dataset_text(there, yaml.string(), out.string()));
  } catch (const std::exception& e) {
    throw core::InputError("", "-o", fmt::format("{} is not a dataset config ({}): repair or remove it, or use "
                                                 "another output directory", yaml.string(), e.what()));
  }
  const std::string mine = config::canonical_text(cfg);
  if (meaning != mine)
    throw core::InputError("", "-o", fmt::format("{} holds another dataset (its dataset.yaml means something else: "
                                                 "{}); use another output directory", out.string(),
                                                 first_difference(meaning, mine)));
  return there;
}

/// Removes what interrupted runs left: this task's shard temporaries, and atomic-write
/// temporaries (`NAME.tmp-PID`) of processes that no longer run on this host.
void remove_leftovers(const fs::path& out, const GenerateOptions& opt, std::int64_t n_shards) {
  std::error_code ec;
  for (std::int64_t k = opt.task_index; k < n_shards; k += opt.task_count)
    fs::remove((out / "shards" / shard_name(k)).string() + ".tmp", ec);
  static const std::regex tmp(R"(.*\.tmp-(\d+))");
  for (const auto& sub : {out, out / "reports", out / "records"})
    for (const auto& e : fs::directory_iterator(sub, ec)) {
      std::smatch m;
      const std::string f = e.path().filename().string();
      if (std::regex_match(f, m, tmp) && ::kill(pid_t(std::stol(m[1])), 0) != 0 && errno == ESRCH)
        fs::remove(e.path(), ec);
    }
}

/// This task's shards still to write: absent ones, and those on disk that fail verification
/// (removed here, with a line saying why).
std::vector<std::int64_t> shards_to_do(const config::DatasetConfig& cfg, const GenerateOptions& opt,
                                       const std::string& hash, std::int64_t n_shards, std::int64_t& done_before) {
  std::vector<std::int64_t> todo;
  std::error_code ec;
  for (std::int64_t k = opt.task_index; k < n_shards; k += opt.task_count) {
    const fs::path p = fs::path(opt.output_dir) / "shards" / shard_name(k);
    if (fs::exists(p, ec)) {
      const std::string problem = shard_problem(opt.output_dir, shard_identity(cfg, hash, k));
      if (problem.empty()) {
        ++done_before;
        continue;
      }
      core::log_line(MPI_COMM_SELF, core::Verbosity::quiet,
                     fmt::format("[generate] {}: {}: redoing it", p.string(), problem));
      fs::remove(p, ec);
    }
    fs::remove(record_path(opt.output_dir, k), ec);
    todo.push_back(k);
  }
  return todo;
}

/// Rank 0's side of the output: checks (path, identity, size and free space) before anything is
/// written, then the directory, the lock, dataset.yaml, and the shards this task still has to
/// write. Throws InputError.
OutputState open_output(const config::DatasetConfig& cfg, const GenerateOptions& opt, const DatasetEstimate& est,
                        std::int64_t n_shards) {
  const fs::path out(opt.output_dir);
  std::error_code ec;
  if (fs::exists(out, ec) && !fs::is_directory(out, ec))
    throw core::InputError("", "-o", "output exists and is not a directory: " + out.string());
  OutputState st;
  st.text = dataset_text(cfg, out);
  // Shapes still to write: this task's share, less the shards on disk (one listing: a huge
  // count must be refused at once, not after a stat per shard).
  double missing = double(cfg.n_shapes) / opt.task_count;
  for (const auto& e : fs::directory_iterator(out / "shards", ec)) {
    std::int64_t k = -1;
    if (std::sscanf(e.path().filename().c_str(), "shard-%ld.h5", &k) == 1 && e.path().extension() == ".h5" &&
        k >= 0 && k < n_shards && k % opt.task_count == opt.task_index)
      missing -= double(shapes_in_shard(cfg, k));
  }
  check_resources(cfg, est, est.bytes_per_shape * std::max(0.0, missing), opt.output_dir, opt.force);
  fs::create_directories(out / "shards", ec);
  if (ec || access(out.c_str(), W_OK) != 0 || access((out / "shards").c_str(), W_OK) != 0)
    throw core::InputError("", "-o", "cannot create or write the output directory " + out.string() +
                                         (ec ? ": " + ec.message() : ""));
  fs::create_directories(out / "reports", ec);
  st.lock = std::make_unique<OutputLock>(opt.output_dir, opt.task_index, opt.task_count);
  if (!st.lock->note().empty()) core::log_line(MPI_COMM_SELF, core::Verbosity::normal, "[generate] " + st.lock->note());
  st.text = dataset_text(cfg, out);  // again, under the lock
  if (st.text == cfg.text && read_text(out / "dataset.yaml") != cfg.text) write_atomically(out / "dataset.yaml", cfg.text);
  remove_leftovers(out, opt, n_shards);
  st.hash = config_hash(cfg);
  st.todo = shards_to_do(cfg, opt, st.hash, n_shards, st.done_before);
  return st;
}

/// Every check before anything is written (options, PETSc options by a trial solve; on rank 0
/// the output, its identity and the free space), then rank 0's output state on every rank; the
/// interrupt handlers from here on. Collective; throws InputError on every rank alike.
OutputState prepare_run(MPI_Comm comm, const config::DatasetConfig& cfg, const GenerateOptions& opt,
                        const DatasetEstimate& est, std::int64_t n_shards) {
  int rank = 0, size = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  if (opt.task_count < 1 || opt.task_index < 0 || opt.task_index >= opt.task_count)
    throw core::InputError("", "--task-index", fmt::format("must be in [0, {}) (--task-count)", opt.task_count));
  if (opt.group_size < 1 || opt.group_size > size)
    throw core::InputError("", "--group-size", fmt::format("must be in [1, {}] (the number of ranks)", size));
  check_petsc_options(cfg, user_options(cfg, opt.petsc_command_line));
  core::info(comm, "[generate] estimate: about {} on disk and {} of CPU for the whole dataset (rough: ~{:.0f} nodes "
             "per shape)", format_bytes(est.bytes), format_duration(est.cpu_seconds), est.nodes_per_shape);
  OutputState out;
  core::on_root(comm, [&] { out = open_output(cfg, opt, est, n_shards); });
  core::install_interrupt_handlers("generate", rank);
  broadcast_output(comm, out);
  return out;
}

io::ShardHeader shard_header(const config::DatasetConfig& cfg, const OutputState& out,
                             const std::map<std::string, std::string>& software, std::int64_t k) {
  io::ShardHeader h;
  h.dataset_name = cfg.name;
  h.config_text = out.text;
  h.scene_text = config::effects_yaml(cfg.scene);
  h.config_hash = out.hash;
  h.seed = cfg.seed;
  h.dim = cfg.shapes.dim;
  h.shard_index = k;
  h.first_shape = k * cfg.shard_size;
  h.n_shapes = shapes_in_shard(cfg, k);
  h.n_loads = cfg.loads.count;
  h.software = software;
  return h;
}

/// One shape's counters into this rank's report (summed over group roots by reduce_report).
void add_to_report(const ShapeJobResult& r, RunReport& rep) {
  rep.shapes += 1;
  rep.shapes_failed += r.entry.ok ? 0 : 1;
  rep.loads_ok += r.loads_ok;
  rep.loads_failed += r.loads_failed;
  rep.newton_iterations += r.newton_iterations;
  rep.solves += r.solves;
  rep.failed_increments += r.failed_increments;
  rep.recovery_iterations += r.recovery_iterations;
  rep.linear += r.linear;
  const auto find = [&](const std::string& name) -> const io::Array* {
    for (const auto& a : r.entry.arrays)
      if (a.name == name) return &a;
    return nullptr;
  };
  const io::Array* est = find("loads/error_estimate_rel_l2");
  const io::Array* status = find("loads/status");
  if (!est || !status) return;
  const auto& v = std::get<std::vector<double>>(est->data);
  const auto& st = std::get<std::vector<std::int8_t>>(status->data);
  auto& s = rep.label_error;
  for (std::size_t k = 0; k < v.size() && k < st.size(); ++k) {
    if (!st[k]) continue;
    if (v[k] < 0) {  // -1: no estimate could be formed
      s.missing += 1;
      continue;
    }
    s.n += 1, s.sum += v[k], s.max = std::max(s.max, v[k]);
    s.above_1_percent += v[k] > 0.01, s.above_5_percent += v[k] > 0.05;
  }
}

/// The run report's numbers over `comm`: counters summed over the group roots (each holds its
/// group's once), phase times likewise, factorisation time over all ranks, the wall time as
/// the slowest rank's, and peak memory per rank gathered to rank 0 (`rss`). Collective.
void reduce_report(MPI_Comm comm, bool group_root, const core::PhaseTimes& times, std::int64_t shards_written,
                   double start, RunReport& rep, std::vector<double>& rss) {
  double pc_setup = 0;
  {
    PetscLogEvent ev;
    PetscEventPerfInfo info{};
    if (PetscLogEventGetId("PCSetUp", &ev) == 0 && PetscLogEventGetPerfInfo(0, ev, &info) == 0) pc_setup = info.time;
  }
  // Counters: the group roots hold the group's numbers once.
  auto sum_roots = [&](std::int64_t v) {
    std::int64_t x = group_root ? v : 0, total = 0;
    MPI_Allreduce(&x, &total, 1, MPI_INT64_T, MPI_SUM, comm);
    return total;
  };
  rep.shapes = sum_roots(rep.shapes);
  rep.shapes_failed = sum_roots(rep.shapes_failed);
  rep.loads_ok = sum_roots(rep.loads_ok);
  rep.loads_failed = sum_roots(rep.loads_failed);
  rep.newton_iterations = sum_roots(rep.newton_iterations);
  rep.solves = sum_roots(rep.solves);
  rep.failed_increments = sum_roots(rep.failed_increments);
  rep.recovery_iterations = sum_roots(rep.recovery_iterations);
  for (std::int64_t* c : {&rep.linear.numeric_factorizations, &rep.linear.symbolic_factorizations,
                          &rep.linear.krylov_iterations, &rep.linear.tangent_assemblies})
    *c = sum_roots(*c);
  rep.shards_written = sum_roots(shards_written);
  for (std::int64_t* c : {&rep.label_error.n, &rep.label_error.missing, &rep.label_error.above_1_percent,
                          &rep.label_error.above_5_percent})
    *c = sum_roots(*c);
  {
    double x[2] = {group_root ? rep.label_error.sum : 0.0, group_root ? rep.label_error.max : 0.0}, t[2];
    MPI_Allreduce(&x[0], &t[0], 1, MPI_DOUBLE, MPI_SUM, comm);
    MPI_Allreduce(&x[1], &t[1], 1, MPI_DOUBLE, MPI_MAX, comm);
    rep.label_error.sum = t[0], rep.label_error.max = t[1];
  }
  const std::vector<std::string> phases = {"shape", "mesh", "setup", "solve", "alpha_search",
                                           "error_estimate", "representations", "gather", "io"};
  for (const auto& p : phases) {
    double x = group_root ? times.get(p) : 0, total = 0;
    MPI_Allreduce(&x, &total, 1, MPI_DOUBLE, MPI_SUM, comm);
    rep.phase_seconds[p] = total;
  }
  MPI_Allreduce(&pc_setup, &rep.factorization_seconds, 1, MPI_DOUBLE, MPI_SUM, comm);
  int size = 1;
  MPI_Comm_size(comm, &size);
  rss.resize(static_cast<std::size_t>(size));
  double mine = peak_rss_mib();
  MPI_Gather(&mine, 1, MPI_DOUBLE, rss.data(), 1, MPI_DOUBLE, 0, comm);
  rep.seconds = core::now_seconds() - start;
  double max_seconds = 0;
  MPI_Allreduce(&rep.seconds, &max_seconds, 1, MPI_DOUBLE, MPI_MAX, comm);
  rep.seconds = max_seconds;
}

/// Rank 0: the task's report (reports/task-I-of-N.json), then the index step when every shard
/// exists (the last task of an array does it). Returns whether the dataset was indexed.
bool report_and_index(const config::DatasetConfig& cfg, const GenerateOptions& opt, int size, RunReport& rep,
                      const std::vector<double>& rss, const std::map<std::string, std::string>& software) {
  bool complete = false;
  nlohmann::json j;
  j["dataset"] = cfg.name;
  j["config"] = cfg.source;
  j["task_index"] = opt.task_index;
  j["task_count"] = opt.task_count;
  j["ranks"] = size;
  j["group_size"] = opt.group_size;
  j["shards"] = {{"total", rep.shards_total}, {"done_before", rep.shards_done_before},
                 {"written", rep.shards_written}};
  j["shapes"] = {{"solved", rep.shapes}, {"failed", rep.shapes_failed}};
  j["load_cases"] = {{"converged", rep.loads_ok}, {"failed", rep.loads_failed},
                     {"per_second", (rep.loads_ok + rep.loads_failed) / std::max(1e-9, rep.seconds)}};
  j["solver"] = {{"newton_iterations", rep.newton_iterations}, {"nonlinear_solves", rep.solves},
                 {"failed_increments", rep.failed_increments},
                 {"recovery_iterations", rep.recovery_iterations},
                 {"numeric_factorizations", rep.linear.numeric_factorizations},
                 {"symbolic_factorizations", rep.linear.symbolic_factorizations},
                 {"krylov_iterations", rep.linear.krylov_iterations},
                 {"tangent_assemblies", rep.linear.tangent_assemblies}};
  {
    const auto& e = rep.label_error;
    j["label_error_estimate"] = {{"load_cases", e.n},
                                 {"mean_rel_l2", e.n ? e.sum / double(e.n) : 0.0},
                                 {"max_rel_l2", e.max},
                                 {"above_1_percent", e.above_1_percent},
                                 {"above_5_percent", e.above_5_percent},
                                 {"without_estimate", e.missing}};
  }
  j["seconds"] = {{"wall", rep.seconds}, {"phases_summed_over_groups", rep.phase_seconds},
                  {"factorization_PCSetUp_summed_over_ranks", rep.factorization_seconds}};
  j["peak_rss_mib_per_rank"] = rss;
  j["software"] = software;
  rep.json = j.dump(2);
  write_atomically(fs::path(opt.output_dir) / "reports" /
                       fmt::format("task-{:03d}-of-{:03d}.json", opt.task_index, opt.task_count),
                   rep.json + "\n");
  bool all = true;
  for (std::int64_t k = 0; k < rep.shards_total && all; ++k)
    all = fs::exists(fs::path(opt.output_dir) / "shards" / shard_name(k));
  if (all) {
    index_dataset(opt.output_dir);
    complete = true;
  }
  return complete;
}

}  // namespace

RunReport generate(MPI_Comm comm, const config::DatasetConfig& cfg, const GenerateOptions& opt) {
  const double start = core::now_seconds();
  int rank = 0, size = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  RunReport rep;
  const std::int64_t S = cfg.shard_size;
  rep.shards_total = (cfg.n_shapes + S - 1) / S;
  // The base surface is read (and so checked) before anything is written.
  const std::optional<geometry::Boundary> base = load_dataset_base(cfg);
  const DatasetEstimate est = estimate_dataset(cfg);
  OutputState out = prepare_run(comm, cfg, opt, est, rep.shards_total);
  std::vector<std::int64_t>& todo = out.todo;
  const std::int64_t done_before = out.done_before;
  rep.shards_done_before = done_before;
  HS_PETSC(PetscLogDefaultBegin());

  std::int64_t todo_shapes = 0;
  for (auto k : todo) todo_shapes += std::min<std::int64_t>(S, cfg.n_shapes - k * S);
  const std::int64_t todo_loads = todo_shapes * cfg.loads.count;
  core::info(comm, "[generate] {}: {} shapes x {} load cases, {} shards ({} done before, {} to do by task {}/{}), "
             "{} ranks in groups of {} -> {}",
             cfg.name, cfg.n_shapes, cfg.loads.count, rep.shards_total, done_before, todo.size(),
             opt.task_index, opt.task_count, size, opt.group_size, opt.output_dir);

  MPI_Comm group;
  MPI_Comm_split(comm, rank / opt.group_size, rank, &group);
  int grank = 0;
  MPI_Comm_rank(group, &grank);
  const bool group_root = grank == 0;
  const std::string& hash = out.hash;
  const auto software = software_versions();

  core::PhaseTimes times;
  std::int64_t shards_written = 0;
  double last_print = core::now_seconds();
  auto print_progress = [&](SharedCounters& c, bool force) {
    if (rank != 0 || opt.progress_seconds <= 0) return;
    const double now = core::now_seconds();
    if (!force && now - last_print < opt.progress_seconds) return;
    last_print = now;
    const auto v = c.read();
    const std::int64_t loads = v[loads_ok] + v[loads_failed];
    const double rate = loads / std::max(1e-9, now - start);
    core::info(comm, "[generate] {}/{} shapes, {}/{} load cases ({} failed, {} shapes failed), {:.2f} load cases/s, "
               "elapsed {}, ETA {}", v[shapes_done], todo_shapes, loads, todo_loads, v[loads_failed],
               v[shapes_failed], rate, format_duration(now - start),
               format_duration(rate > 0 ? (todo_loads - loads) / rate : NAN));
  };
  {
    SharedCounters counters(comm);
    while (true) {
      std::int64_t slot = 0;
      if (group_root) slot = counters.fetch_add(next_shard, 1);
      MPI_Bcast(&slot, 1, MPI_INT64_T, 0, group);
      if (slot >= std::int64_t(todo.size())) break;
      const std::int64_t k = todo[std::size_t(slot)];
      const std::int64_t first = k * S, n = std::min(S, cfg.n_shapes - first);
      std::unique_ptr<io::ShardWriter> writer;
      if (group_root) {
        check_shard_space(opt.output_dir, k, est.bytes_per_shape * double(n));
        writer = std::make_unique<io::ShardWriter>((fs::path(opt.output_dir) / "shards" / shard_name(k)).string(),
                                                   shard_header(cfg, out, software, k));
      }
      for (std::int64_t id = first; id < first + n; ++id) {
        ShapeJobResult r = run_shape(group, cfg, base, id, [&](bool ok) {
          if (group_root) counters.fetch_add(ok ? loads_ok : loads_failed, 1);
          print_progress(counters, false);
        });
        if (group_root) {
          if (!r.entry.ok) counters.fetch_add(loads_failed, r.loads_failed);
          counters.fetch_add(shapes_done, 1);
          if (!r.entry.ok) counters.fetch_add(shapes_failed, 1);
          auto t = times.scope("io");
          writer->add(r.entry);
        }
        for (const auto& [name, s] : r.times.all()) times.add(name, s);
        add_to_report(r, rep);
        if (!r.entry.ok)
          core::log_line(MPI_COMM_SELF, core::Verbosity::normal,
                         fmt::format("[generate] shape {} failed: {}", id, r.entry.failure.substr(0, 300)));
      }
      if (group_root) {
        auto t = times.scope("io");
        writer->commit([&](std::uint32_t crc, std::uint64_t bytes) {
          write_shard_record(opt.output_dir, shard_identity(cfg, hash, k), crc, bytes);
        });
        ++shards_written;
      }
    }
    // Rank 0 keeps the progress line going until every group is done.
    if (rank == 0 && opt.progress_seconds > 0) {
      while (true) {
        const auto v = counters.read();
        if (v[shapes_done] >= todo_shapes) break;
        print_progress(counters, false);
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
      }
    }
    MPI_Barrier(comm);
    if (rank == 0 && todo_shapes > 0) print_progress(counters, true);
  }
  MPI_Comm_free(&group);

  std::vector<double> rss;
  reduce_report(comm, group_root, times, shards_written, start, rep, rss);
  int complete = 0;
  core::on_root(comm, [&] { complete = report_and_index(cfg, opt, size, rep, rss, software) ? 1 : 0; });
  MPI_Bcast(&complete, 1, MPI_INT, 0, comm);
  rep.indexed = complete == 1;
  core::remove_interrupt_handlers();
  return rep;
}

std::string report_table(const RunReport& r) {
  std::string s;
  const double loads = double(r.loads_ok + r.loads_failed);
  s += fmt::format("  shapes {} ({} failed), load cases {} converged, {} failed, in {:.1f} s: {:.2f} load cases/s\n",
                   r.shapes, r.shapes_failed, r.loads_ok, r.loads_failed, r.seconds, loads / std::max(1e-9, r.seconds));
  s += fmt::format("  Newton iterations {} in {} increments ({:.1f} per load case); {} failed increments "
                   "cost {} of them\n", r.newton_iterations, r.solves, r.newton_iterations / std::max(1.0, loads),
                   r.failed_increments, r.recovery_iterations);
  const double ok = std::max<double>(1.0, double(r.loads_ok));
  s += fmt::format("  per converged load case: {:.2f} numeric factorisations, {:.2f} symbolic, {:.1f} Krylov "
                   "iterations, {:.1f} tangent assemblies\n", double(r.linear.numeric_factorizations) / ok,
                   double(r.linear.symbolic_factorizations) / ok, double(r.linear.krylov_iterations) / ok,
                   double(r.linear.tangent_assemblies) / ok);
  double total = 0;
  for (const auto& [k, v] : r.phase_seconds) total += v;
  s += "  phase              seconds   share\n";
  for (const auto& [k, v] : r.phase_seconds)
    s += fmt::format("  {:<17s} {:8.2f}  {:5.1f}%\n", k, v, 100 * v / std::max(1e-9, total));
  s += fmt::format("  (factorisations, PCSetUp: {:.2f} s of solve + alpha_search)\n", r.factorization_seconds);
  if (const auto& e = r.label_error; e.n > 0)
    s += fmt::format("  label error estimate (relative L2 of u): mean {:.3g}, max {:.3g}; above 1%: {} of {}, "
                     "above 5%: {}; {} converged load cases without an estimate\n", e.sum / double(e.n), e.max,
                     e.above_1_percent, e.n, e.above_5_percent, e.missing);
  return s;
}

}  // namespace hypershape::factory
