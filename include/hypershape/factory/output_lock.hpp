#pragma once
/// One writer per slice of a dataset directory. A run holds `DIR/.locks/task-I-of-N.lock`
/// (an flock on the file, which the kernel releases when the process dies, even by kill -9;
/// the file names the holder: host, pid, start time). A second run on the same slice is refused
/// with the holder named; the tasks of one SLURM array (same N, other I) write disjoint shards
/// and run side by side; a run with another task count overlaps every slice and is refused
/// while any other slice is held. A lock file nobody holds is stale and taken over.
#include <string>

namespace hypershape::factory {

class OutputLock {
 public:
  /// Takes the lock (creates DIR/.locks). Throws core::InputError (key "-o") naming the run
  /// that holds it. Not collective: call on one rank.
  OutputLock(const std::string& dir, int task_index, int task_count);
  /// Removes the lock file and releases the lock.
  ~OutputLock();
  OutputLock(const OutputLock&) = delete;
  OutputLock& operator=(const OutputLock&) = delete;
  /// A line about stale locks that were taken over (empty: none).
  const std::string& note() const { return note_; }

 private:
  void release();
  std::string path_, note_;
  int fd_ = -1;
  int slot_ = -1;  ///< core::register_temporary: a signal removes the lock file too
};

}  // namespace hypershape::factory
