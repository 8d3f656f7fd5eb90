// The engines of `skycal batch`: where the chunks run (batch_local_engine.cc,
// batch_slurm_engine.cc; their process helpers in batch_process.h). Both start skycal itself (the
// running binary, /proc/self/exe) as `skycal batch --worker-chunk K --out DIR`.
#pragma once
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "skycal/batch/batch_plan.h"
#include "skycal/batch/batch.h"

namespace skycal::batch {

// local: a pool of at most `jobs` child processes, one chunk each, over the plan's pending
// chunks; each child's log goes to logs/chunk-K.log. Prints progress while it waits.
// Returns {chunks, exits: [{chunk, status}]}; frame failures are in the state files.
nlohmann::json RunLocalEngine(const std::string& out_dir, const BatchPlan& plan, int jobs);

// slurm: one `sbatch --array` over the pending chunks and one reduce job depending on it
// with afterok (--kill-on-invalid-dep=yes: a failed chunk cancels the reduce, which never
// stays pending). Polls squeue until both leave the queue, printing progress; then reads
// `scontrol show job` for each task's state. Returns {array_job, reduce_job, tasks,
// reduce_state}. Throws when sbatch is missing or refuses the job.
nlohmann::json RunSlurmEngine(const std::string& out_dir, const BatchPlan& plan, const BatchOptions& options);

// Throws, naming what is missing, unless sbatch, squeue and scontrol are on PATH.
void RequireSlurmClient();

// The running binary's absolute path (/proc/self/exe).
std::string SelfExecutable();

}  // namespace skycal::batch
