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
#include "hypershape/core/platform.hpp"
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
  return {{"petsc", petsc}, {"gmsh", mesh::gmsh_version()}, {"numerics", core::numerics_platform()}};
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
  core::info(comm, "[generate] estimate: {}", est.line());
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
  rep.counters += r.counters;
  rep.label_error += r.label_error;
  rep.accuracy += r.accuracy;
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
    // PETSc's factorisations are PCSetUp; the single-precision (SMUMPS) and the 2D blocked ones are not.
    for (const char* name : {"PCSetUp", "HSFactorSingle", "HSFactorBlocked"})
      if (PetscLogEventGetId(name, &ev) == 0 && PetscLogEventGetPerfInfo(0, ev, &info) == 0) pc_setup += info.time;
  }
  // Counters: the group roots hold the group's numbers once.
  auto sum_roots = [&](std::int64_t v) {
    std::int64_t x = group_root ? v : 0, total = 0;
    MPI_Allreduce(&x, &total, 1, MPI_INT64_T, MPI_SUM, comm);
    return total;
  };
  rep.shapes = sum_roots(rep.shapes);
  rep.shapes_failed = sum_roots(rep.shapes_failed);
  rep.counters.sum_over(comm, group_root);
  rep.shards_written = sum_roots(shards_written);
  rep.label_error.sum_over(comm, group_root);
  rep.accuracy.sum_over(comm, group_root);
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
  const SolveCounters& c = rep.counters;
  j["load_cases"] = {{"converged", c.loads_ok}, {"failed", c.loads_failed},
                     {"per_second", double(c.loads()) / std::max(1e-9, rep.seconds)}};
  j["solver"] = c.solver_json();
  j["label_error_estimate"] = rep.label_error.json();
  if (cfg.accuracy.enabled()) j["accuracy"] = rep.accuracy.json(cfg.accuracy);
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

/// The progress line (rank 0, every `progress_seconds`): shapes and load cases done of this
/// task's, failures, rate, elapsed time and ETA.
class Progress {
 public:
  Progress(MPI_Comm comm, const GenerateOptions& opt, double start, std::int64_t todo_shapes, std::int64_t todo_loads)
      : comm_(comm), period_(opt.progress_seconds), start_(start), last_(start), todo_shapes_(todo_shapes),
        todo_loads_(todo_loads), on_(core::rank(comm) == 0 && opt.progress_seconds > 0) {}
  void print(SharedCounters& c, bool force) {
    if (!on_) return;
    const double now = core::now_seconds();
    if (!force && now - last_ < period_) return;
    last_ = now;
    const auto v = c.read();
    const std::int64_t loads = v[loads_ok] + v[loads_failed];
    const double rate = double(loads) / std::max(1e-9, now - start_);
    core::info(comm_, "[generate] {}/{} shapes, {}/{} load cases ({} failed, {} shapes failed), {:.2f} load cases/s, "
               "elapsed {}, ETA {}", v[shapes_done], todo_shapes_, loads, todo_loads_, v[loads_failed],
               v[shapes_failed], rate, format_duration(now - start_),
               format_duration(rate > 0 ? double(todo_loads_ - loads) / rate : NAN));
  }
  /// Rank 0 keeps the line going until every group is done.
  void until_done(SharedCounters& c) {
    if (!on_) return;
    while (c.read()[shapes_done] < todo_shapes_) {
      print(c, false);
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
  }

 private:
  MPI_Comm comm_;
  double period_, start_, last_;
  std::int64_t todo_shapes_, todo_loads_;
  bool on_;
};

/// The solver groups' work: shards taken from the shared queue one at a time, each solved shape
/// by shape and written (group root) under a temporary name, recorded, renamed.
class ShardRunner {
 public:
  ShardRunner(MPI_Comm comm, const config::DatasetConfig& cfg, const GenerateOptions& opt, const OutputState& out,
              const std::optional<geometry::Boundary>& base, const DatasetEstimate& est, RunReport& rep)
      : cfg_(cfg), opt_(opt), out_(out), base_(base), est_(est), rep_(rep), software_(software_versions()) {
    MPI_Comm_split(comm, core::rank(comm) / opt.group_size, core::rank(comm), &group_);
    group_root_ = core::rank(group_) == 0;
  }
  ~ShardRunner() { MPI_Comm_free(&group_); }
  ShardRunner(const ShardRunner&) = delete;
  ShardRunner& operator=(const ShardRunner&) = delete;

  void run(SharedCounters& counters, Progress& progress) {
    while (true) {
      std::int64_t slot = 0;
      if (group_root_) slot = counters.fetch_add(next_shard, 1);
      MPI_Bcast(&slot, 1, MPI_INT64_T, 0, group_);
      if (slot >= std::int64_t(out_.todo.size())) break;
      run_shard(out_.todo[std::size_t(slot)], counters, progress);
    }
  }
  bool group_root() const { return group_root_; }
  const core::PhaseTimes& times() const { return times_; }
  std::int64_t shards_written() const { return shards_written_; }
  const std::map<std::string, std::string>& software() const { return software_; }

 private:
  void run_shard(std::int64_t k, SharedCounters& counters, Progress& progress) {
    const std::int64_t S = cfg_.shard_size, first = k * S, n = std::min(S, cfg_.n_shapes - first);
    std::unique_ptr<io::ShardWriter> writer;
    if (group_root_) {
      check_shard_space(opt_.output_dir, k, est_.bytes_per_shape * double(n));
      writer = std::make_unique<io::ShardWriter>((fs::path(opt_.output_dir) / "shards" / shard_name(k)).string(),
                                                 shard_header(cfg_, out_, software_, k));
    }
    for (std::int64_t id = first; id < first + n; ++id) {
      ShapeJobResult r = run_shape(group_, cfg_, base_, id, [&](bool ok) {
        if (group_root_) counters.fetch_add(ok ? loads_ok : loads_failed, 1);
        progress.print(counters, false);
      });
      if (group_root_) {
        if (!r.entry.ok) counters.fetch_add(loads_failed, r.counters.loads_failed);
        counters.fetch_add(shapes_done, 1);
        if (!r.entry.ok) counters.fetch_add(shapes_failed, 1);
        auto t = times_.scope("io");
        writer->add(r.entry);
      }
      for (const auto& [name, sec] : r.times.all()) times_.add(name, sec);
      add_to_report(r, rep_);
      if (!r.entry.ok)
        core::log_line(MPI_COMM_SELF, core::Verbosity::normal,
                       fmt::format("[generate] shape {} failed: {}", id, r.entry.failure.substr(0, 300)));
    }
    if (!group_root_) return;
    auto t = times_.scope("io");
    writer->commit([&](std::uint32_t crc, std::uint64_t bytes) {
      write_shard_record(opt_.output_dir, shard_identity(cfg_, out_.hash, k), crc, bytes);
    });
    ++shards_written_;
  }

  MPI_Comm group_;
  bool group_root_ = false;
  const config::DatasetConfig& cfg_;
  const GenerateOptions& opt_;
  const OutputState& out_;
  const std::optional<geometry::Boundary>& base_;
  const DatasetEstimate& est_;
  RunReport& rep_;
  std::map<std::string, std::string> software_;
  core::PhaseTimes times_;
  std::int64_t shards_written_ = 0;
};

}  // namespace

RunReport generate(MPI_Comm comm, const config::DatasetConfig& cfg, const GenerateOptions& opt) {
  const double start = core::now_seconds();
  const int size = core::size(comm);
  RunReport rep;
  rep.accuracy_config = cfg.accuracy;
  const std::int64_t S = cfg.shard_size;
  rep.shards_total = (cfg.n_shapes + S - 1) / S;
  // The base surface is read (and so checked) before anything is written.
  const std::optional<geometry::Boundary> base = load_dataset_base(cfg);
  const DatasetEstimate est = estimate_dataset(cfg, base);
  OutputState out = prepare_run(comm, cfg, opt, est, rep.shards_total);
  rep.shards_done_before = out.done_before;
  HS_PETSC(PetscLogDefaultBegin());
  std::int64_t todo_shapes = 0;
  for (auto k : out.todo) todo_shapes += std::min<std::int64_t>(S, cfg.n_shapes - k * S);
  const std::int64_t todo_loads = todo_shapes * cfg.loads.count;
  core::info(comm, "[generate] {}: {} shapes x {} load cases, {} shards ({} done before, {} to do by task {}/{}), "
             "{} ranks in groups of {} -> {}",
             cfg.name, cfg.n_shapes, cfg.loads.count, rep.shards_total, out.done_before, out.todo.size(),
             opt.task_index, opt.task_count, size, opt.group_size, opt.output_dir);
  ShardRunner runner(comm, cfg, opt, out, base, est, rep);
  {
    SharedCounters counters(comm);
    Progress progress(comm, opt, start, todo_shapes, todo_loads);
    runner.run(counters, progress);
    progress.until_done(counters);
    MPI_Barrier(comm);
    if (todo_shapes > 0) progress.print(counters, true);
  }
  std::vector<double> rss;
  reduce_report(comm, runner.group_root(), runner.times(), runner.shards_written(), start, rep, rss);
  int complete = 0;
  core::on_root(comm, [&] { complete = report_and_index(cfg, opt, size, rep, rss, runner.software()) ? 1 : 0; });
  MPI_Bcast(&complete, 1, MPI_INT, 0, comm);
  rep.indexed = complete == 1;
  core::remove_interrupt_handlers();
  return rep;
}

std::string report_table(const RunReport& r) {
  std::string s;
  const SolveCounters& c = r.counters;
  const double loads = double(c.loads());
  s += fmt::format("  shapes {} ({} failed), load cases {} converged, {} failed, in {:.1f} s: {:.2f} load cases/s\n",
                   r.shapes, r.shapes_failed, c.loads_ok, c.loads_failed, r.seconds, loads / std::max(1e-9, r.seconds));
  s += fmt::format("  Newton iterations {} in {} increments ({:.1f} per load case); {} failed increments "
                   "cost {} of them\n", c.newton_iterations, c.solves, double(c.newton_iterations) / std::max(1.0, loads),
                   c.failed_increments, c.recovery_iterations);
  const double ok = std::max<double>(1.0, double(c.loads_ok));
  s += fmt::format("  per converged load case: {:.2f} numeric factorisations, {:.2f} symbolic, {:.1f} Krylov "
                   "iterations, {:.1f} tangent assemblies\n", double(c.linear.numeric_factorizations) / ok,
                   double(c.linear.symbolic_factorizations) / ok, double(c.linear.krylov_iterations) / ok,
                   double(c.linear.tangent_assemblies) / ok);
  double total = 0;
  for (const auto& [k, v] : r.phase_seconds) total += v;
  s += "  phase              seconds   share\n";
  for (const auto& [k, v] : r.phase_seconds)
    s += fmt::format("  {:<17s} {:8.2f}  {:5.1f}%\n", k, v, 100 * v / std::max(1e-9, total));
  s += fmt::format("  (factorisations, PCSetUp: {:.2f} s of solve + alpha_search)\n", r.factorization_seconds);
  s += r.label_error.line();
  s += r.accuracy.line(r.accuracy_config);
  return s;
}

}  // namespace hypershape::factory
