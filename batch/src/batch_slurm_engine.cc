// The Slurm engine of `skycal batch`: an sbatch array over the chunks and an afterok reduce.
#include "batch_engines.h"

#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <map>
#include <sstream>
#include <thread>

#include "batch_process.h"
#include "skycal/core/atomic_file.h"
#include "skycal/core/error.h"
#include "skycal/core/json_file.h"

namespace skycal::batch {
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {

// Parses `scontrol show job ID` (one record per array task, blank-line separated) into
// {ArrayTaskId or JobId -> {JobState, ExitCode, Reason}}.
nlohmann::json ParseScontrol(const std::string& text) {
  nlohmann::json tasks = nlohmann::json::array();
  std::stringstream records(text);
  std::string rec, line;
  nlohmann::json cur = nlohmann::json::object();
  auto flush = [&] {
    if (!cur.empty()) tasks.push_back(cur);
    cur = nlohmann::json::object();
  };
  while (std::getline(records, line)) {
    if (line.find_first_not_of(" \t") == std::string::npos) {
      flush();
      continue;
    }
    std::stringstream words(line);
    for (std::string w; words >> w;) {
      const auto eq = w.find('=');
      if (eq == std::string::npos) continue;
      const std::string k = w.substr(0, eq);
      if (k == "JobId" || k == "ArrayJobId" || k == "ArrayTaskId" || k == "JobState" || k == "Reason" || k == "ExitCode") {
        cur[k] = w.substr(eq + 1);
      }
    }
  }
  flush();
  return tasks;
}

std::string FirstToken(std::string s) {
  const auto end = s.find_first_of(";\n\r ");
  return end == std::string::npos ? s : s.substr(0, end);
}

}  // namespace

void RequireSlurmClient() {
  const std::string sbatch = FindOnPath("sbatch");
  if (sbatch.empty()) {
    throw Error("BatchOptions::engine = slurm: sbatch not found on PATH (install the Slurm client, Debian's "
                "slurm-client, and point SLURM_CONF at the cluster's slurm.conf; or use BatchOptions::engine = local)");
  }
  if (FindOnPath("squeue").empty() || FindOnPath("scontrol").empty()) {
    throw Error("BatchOptions::engine = slurm: squeue or scontrol not found on PATH beside " + sbatch +
                " (the Slurm client)");
  }
}

namespace {
// An earlier submission into the same --out still queued: refuse rather than race it.
void RefuseIfEarlierJobsQueued(const std::string& out_dir, const fs::path& sdir, const std::string& squeue) {
  std::error_code ec;
  if (!fs::exists(sdir / "jobs.json", ec)) return;
  const nlohmann::json earlier = ReadJsonFile((sdir / "jobs.json").string());
  std::string ids;
  for (const char* k : {"array_job", "reduce_job"}) {
    const std::string id = earlier.value(k, std::string());
    if (!id.empty()) ids += (ids.empty() ? "" : ",") + id;
  }
  if (ids.empty()) return;
  const Captured q = RunCapture({squeue, "-h", "-j", ids, "-o", "%i %T"});
  if (q.status == 0 && q.out.find_first_not_of(" \n") != std::string::npos) {
    throw Error("BatchOptions::out_dir = " + out_dir + ": its earlier Slurm jobs (" + ids + ") are still in the queue:\n" +
                q.out + "wait for them (or scancel them), then run again with BatchOptions::resume");
  }
}

std::string ShellQuote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

// slurm/chunk.sh and slurm/reduce.sh: each execs this binary on one chunk, or the reduce.
struct JobScripts {
  std::string chunk, reduce;
};

JobScripts WriteJobScripts(const fs::path& sdir, const std::string& exe, const std::string& out_abs) {
  auto script = [&](const std::string& name, const std::string& body) {
    const std::string p = (sdir / name).string();
    WriteFileAtomically(p, "#!/bin/sh\n# written by skycal batch: one " + body);
    ::chmod(p.c_str(), 0755);
    return p;
  };
  JobScripts js;
  js.chunk = script("chunk.sh", "chunk of the batch (the array task id is the chunk)\nexec " + ShellQuote(exe) +
                                    " batch --worker-chunk \"$SLURM_ARRAY_TASK_ID\" --out " + ShellQuote(out_abs) + "\n");
  js.reduce = script("reduce.sh", "reduce of the batch\nexec " + ShellQuote(exe) + " batch --reduce --out " +
                                      ShellQuote(out_abs) + "\n");
  return js;
}

// The pending chunks as one job array; returns its job id.
std::string SubmitChunkArray(const std::string& sbatch, const std::vector<int>& pending, const std::string& out_abs,
                             const BatchOptions& o, const std::string& chunk_sh) {
  std::string array;
  for (int c : pending) {  // appended piecewise: GCC 12 warns (-Wrestrict, a false positive) on "," + string
    if (!array.empty()) array += ',';
    array += std::to_string(c);
  }
  std::vector<std::string> args = {sbatch, "--parsable", "--job-name=skycal-batch", "--array=" + array,
                                   "--chdir=" + out_abs, "--output=" + LogPath(out_abs, "chunk-%a.log")};
  args.insert(args.end(), o.slurm_options.begin(), o.slurm_options.end());
  args.push_back(chunk_sh);
  const Captured c = RunCapture(args);
  const std::string array_id = FirstToken(c.out);
  if (c.status != 0 || array_id.empty()) {
    throw Error("BatchOptions::engine = slurm: sbatch refused the chunk array (" + DescribeWaitStatus(c.status) +
                "; its message is above)");
  }
  BatchLog("submitted the chunk array: job " + array_id + " (" + std::to_string(pending.size()) + " tasks: " + array + ")");
  return array_id;
}

// The reduce, after the array when there is one; a refusal cancels the array.
std::string SubmitReduce(const std::string& sbatch, const std::string& array_id, const std::string& out_abs,
                         const BatchOptions& o, const std::string& reduce_sh) {
  std::vector<std::string> rargs = {sbatch, "--parsable", "--job-name=skycal-reduce", "--chdir=" + out_abs,
                                    "--output=" + LogPath(out_abs, "reduce.log")};
  if (!array_id.empty()) {
    rargs.push_back("--dependency=afterok:" + array_id);
    rargs.push_back("--kill-on-invalid-dep=yes");
  }
  rargs.insert(rargs.end(), o.slurm_options.begin(), o.slurm_options.end());
  rargs.push_back(reduce_sh);
  const Captured rc = RunCapture(rargs);
  const std::string reduce_id = FirstToken(rc.out);
  if (rc.status != 0 || reduce_id.empty()) {
    if (!array_id.empty()) RunCapture({FindOnPath("scancel"), array_id});
    throw Error("BatchOptions::engine = slurm: sbatch refused the reduce job (" + DescribeWaitStatus(rc.status) +
                "; its message is above); the chunk array " + array_id + " was cancelled");
  }
  BatchLog("submitted the reduce: job " + reduce_id + (array_id.empty() ? "" : " (afterok:" + array_id + ")"));
  return reduce_id;
}

// Polls squeue until every watched job has left the queue, printing progress; returns the
// seconds waited.
double WaitForQueue(const std::string& squeue, const std::vector<std::string>& watch, const std::string& out_dir,
                    const BatchPlan& plan, const BatchOptions& o) {
  std::string ids;
  for (const auto& w : watch) ids += (ids.empty() ? "" : ",") + w;
  ProgressPrinter progress(CountBatchProgress(out_dir, plan).done);
  const auto t0 = Clock::now();
  for (;;) {
    const Captured q = RunCapture({squeue, "-h", "-j", ids, "-o", "%i %T"});
    std::map<std::string, int> states;
    std::stringstream lines(q.out);
    int jobs_listed = 0;
    for (std::string id, state; lines >> id >> state;) {
      ++states[state];
      ++jobs_listed;
    }
    if (jobs_listed == 0) break;  // every job has left the queue (or squeue no longer knows the ids)
    std::string what = "slurm:";
    for (const auto& [s, n] : states) {
      what += ' ';
      what += std::to_string(n);
      what += ' ';
      what += s;
    }
    progress.Update(CountBatchProgress(out_dir, plan), what);
    std::this_thread::sleep_for(std::chrono::duration<double>(o.poll_s));
  }
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// The array's tasks and the reduce as scontrol last saw them; failed tasks are logged.
void RecordJobStates(const std::string& scontrol, const std::string& array_id, const std::string& reduce_id,
                     const std::string& out_abs, nlohmann::json* result) {
  if (!array_id.empty()) {
    const Captured s = RunCapture({scontrol, "show", "job", array_id});
    (*result)["tasks"] = ParseScontrol(s.out);
    for (const auto& t : (*result)["tasks"]) {
      if (t.value("JobState", "") != "COMPLETED") {
        BatchLog("chunk " + t.value("ArrayTaskId", "?") + " (job " + t.value("JobId", "?") + "): " +
                 t.value("JobState", "?") + ", exit " + t.value("ExitCode", "?") + " (log: " +
                 LogPath(out_abs, "chunk-" + t.value("ArrayTaskId", "?") + ".log") + ")");
      }
    }
  }
  const Captured r = RunCapture({scontrol, "show", "job", reduce_id});
  const nlohmann::json rt = ParseScontrol(r.out);
  (*result)["reduce_state"] = rt.empty() ? "unknown (no longer listed by scontrol)" : rt[0].value("JobState", "?");
  if (!rt.empty() && rt[0].contains("Reason")) (*result)["reduce_reason"] = rt[0]["Reason"];
}
}  // namespace

// The chunks as a Slurm job array, the reduce after it, then the queue watched to the end.
nlohmann::json RunSlurmEngine(const std::string& out_dir, const BatchPlan& plan, const BatchOptions& o) {
  RequireSlurmClient();
  const std::string sbatch = FindOnPath("sbatch"), squeue = FindOnPath("squeue"), scontrol = FindOnPath("scontrol");
  const std::vector<int> pending = PendingChunks(out_dir, plan);
  const std::string out_abs = fs::absolute(out_dir).string();
  const fs::path sdir = fs::path(out_abs) / "slurm";
  fs::create_directories(sdir);
  RefuseIfEarlierJobsQueued(out_dir, sdir, squeue);
  const JobScripts js = WriteJobScripts(sdir, SelfExecutable(), out_abs);

  nlohmann::json result = {{"engine", "slurm"}, {"chunks", pending.size()}};
  std::string array_id;
  std::vector<std::string> watch;
  if (!pending.empty()) {
    array_id = SubmitChunkArray(sbatch, pending, out_abs, o, js.chunk);
    watch.push_back(array_id);
  }
  const std::string reduce_id = SubmitReduce(sbatch, array_id, out_abs, o, js.reduce);
  watch.push_back(reduce_id);
  WriteJsonFileAtomically((sdir / "jobs.json").string(), {{"array_job", array_id}, {"reduce_job", reduce_id}, {"chunks", pending}});
  result["array_job"] = array_id;
  result["reduce_job"] = reduce_id;
  result["queue_s"] = WaitForQueue(squeue, watch, out_dir, plan, o);
  RecordJobStates(scontrol, array_id, reduce_id, out_abs, &result);
  return result;
}

}  // namespace skycal::batch
