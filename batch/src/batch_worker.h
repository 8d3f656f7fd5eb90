// The two pieces of `skycal batch` that run as their own processes: one chunk of frames
// (a local pool child or a Slurm array task) and the reduce (in the driver, or a Slurm job).
#pragma once
#include <string>

#include <nlohmann/json.hpp>

#include "skycal/batch/batch_plan.h"
#include "skycal/batch/batch.h"

namespace skycal::batch {

// Fits chunk `chunk` of the plan in --out in time order: frames already done are skipped
// (their preset still warm-starts the next), each other frame is fitted from the previous
// fitted frame's preset (or --init: the chunk's first frame, --cold-start, or after a
// failure) into frames/<name>/, then its state is written. A failed frame is recorded with
// its message and the chunk goes on. Returns {chunk, fitted, failed: [{frame, message}]}.
nlohmann::json RunBatchChunk(const std::string& out_dir, int chunk, const BatchHooks& hooks);

// Requires every frame done (else throws, listing each frame's failure); then the day fit
// (day/), the keyframe tables (tables/) and batch.json. Returns batch.json.
nlohmann::json RunBatchReduce(const std::string& out_dir, const BatchHooks& hooks);

// The not-done frames as "name: message" lines (at most `limit`, then a count).
std::string DescribeUnfinishedFrames(const std::string& out_dir, const BatchPlan& plan, int limit);

}  // namespace skycal::batch
