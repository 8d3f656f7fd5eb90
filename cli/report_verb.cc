#include "report_verb.h"

#include <filesystem>

#include "command_line.h"
#include "skycal/core/error.h"
#include "verb_common.h"

namespace skycal::cli {

namespace {

// Plots are optional: a machine where PLplot cannot draw gets the page without them.
void LogSkippedPlots(const std::string& verb, const report::ReportSummary& s) {
  if (s.plots_skipped == 0) return;
  Log(verb, "plots skipped: " + std::to_string(s.plots_skipped) + " chart(s) left out of the report, " +
                s.plots_skipped_why + "; the results are complete");
}

// The report library's messages name ReportOptions' fields; the user set them with these flags.
std::string WithReportFlags(const std::string& message) {
  static const FieldFlag kFlags[] = {{"ReportOptions::out_path", "--out"}, {"ReportOptions::max_depth", "--depth"}};
  return FieldsAsFlags(message, kFlags);
}

}  // namespace

bool ReportVerbOptions::IsValid(std::string* why) const {
  if (dir.empty()) {
    *why = "expected the directory to report on: skycal report DIR [--out report.html]";
    return false;
  }
  if (report.IsValid(why)) return true;
  *why = WithReportFlags(*why);
  return false;
}

nlohmann::json RunReportImpl(const ReportVerbOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw Error(why);
  Log("report", "reading " + o.dir);
  report::ReportSummary s;
  try {
    s = report::WriteReport(o.dir, o.report);
  } catch (const Error& e) {
    throw Error(WithReportFlags(e.what()));
  }
  Log("report", "wrote " + s.path + " (" + std::to_string(s.bytes / 1024) + " KiB: " + std::to_string(s.fits) + " fit(s), " +
                    std::to_string(s.frames) + " frame(s), " + std::to_string(s.exports) + " export(s), " +
                    std::to_string(s.benches) + " bench run(s), " + std::to_string(s.images) + " images, " +
                    std::to_string(s.plots) + " plots)");
  LogSkippedPlots("report", s);
  return {{"out", s.path},      {"bytes", s.bytes},     {"fits", s.fits},     {"frames", s.frames},
          {"fit_sections", s.fit_sections}, {"exports", s.exports}, {"benches", s.benches}, {"images", s.images}, {"plots", s.plots},
          {"day", s.day}, {"plots_skipped", s.plots_skipped}};
}

ReportVerbOptions ParseReportArgs(int argc, char** argv) {
  VerbCommandLine cl("report",
                     "skycal report: one self-contained HTML page of skycal outputs\n\n"
                     "DIR is a `skycal fit` output (fit.json, fit/<ref>.{reference,fit,error}.png,\n"
                     "preset.json), a directory of several (a day: time-of-day plots of sun illuminance,\n"
                     "haziness, exposure and error), a `skycal export` output (manifest.json, keyframes.json)\n"
                     "or a `skycal bench` output (results.json, Pareto plots), or any directory holding\n"
                     "these up to --depth levels down; a `skycal calibrate` output's day.json adds the day's\n"
                     "wind. Images and plots (PLplot) are embedded: the page can be mailed or archived alone.",
                     "  skycal report DIR [--out report.html] [--title TEXT] [--depth N] [--json]");
  ReportVerbOptions o;
  bool json = false;
  cl.Text("dir", &o.dir, "DIR", "the output directory to report on");
  cl.Text("--out", &o.report.out_path, "FILE.html", "the page to write (default DIR/report.html), atomically");
  cl.Text("--title", &o.report.title, "TEXT", "the page's title (default: skycal report: <DIR's name>)");
  cl.Integer("--depth", &o.report.max_depth, 0, 8, "expected an integer in [0, 8]", "N",
             "directory levels below DIR searched for outputs (default 3)");
  cl.Integer("--max-fit-sections", &o.report.max_fit_sections, 1, 1e6, "expected an integer >= 1", "N",
             "fits shown in full (images, tables), evenly spaced in time (default 24);\n"
             "every fit is in the day's plots and table");
  cl.Flag("--json", &json, "print a JSON summary on stdout (the log goes to stderr)");
  cl.Parse(argc, argv);
  return o;
}

int RunReport(int argc, char** argv) {
  return RunVerb("report", WantsJson(argc, argv), [&]() { return RunReportImpl(ParseReportArgs(argc, argv)); });
}

void WriteVerbReport(const std::string& verb, const std::string& staging_dir, int max_depth) {
  report::ReportOptions ro;
  ro.max_depth = max_depth;
  report::ReportSummary s;
  try {
    s = report::WriteReport(staging_dir, ro);
  } catch (const Error& e) {
    throw Error(std::string("report.html: ") + e.what() + " (--no-report leaves the report out)");
  }
  Log(verb, "report.html: " + std::to_string(s.images) + " images, " + std::to_string(s.plots) + " plots, " +
                std::to_string(s.bytes / 1024) + " KiB");
  LogSkippedPlots(verb, s);
}

}  // namespace skycal::cli
