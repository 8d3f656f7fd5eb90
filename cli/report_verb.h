// `skycal report DIR [--out report.html]`: the self-contained HTML report of a fit, a day of
// fits, an export and/or a bench output directory (report/include/skycal/report/report.h).
#pragma once
#include <string>

#include <nlohmann/json.hpp>

#include "skycal/report/report.h"

namespace skycal::cli {

struct ReportVerbOptions {
  std::string dir;              // the output directory to report on
  report::ReportOptions report;  // --out, --title, --depth
  bool IsValid(std::string* why) const;
};

nlohmann::json RunReportImpl(const ReportVerbOptions& options);
// Parses the arguments after the verb (no I/O). Throws HelpRequested (command_line.h) for
// --help, skycal::Error naming the option on a bad command line.
ReportVerbOptions ParseReportArgs(int argc, char** argv);
int RunReport(int argc, char** argv);

// For the verbs that write a report into their output directory (fit, export, bench, batch):
// writes STAGING/report.html, logging where; `verb` prefixes the log line. `max_depth`:
// directory levels below STAGING searched (0: the verb's own output only; batch: 2, its
// frames/<name>/ fits).
void WriteVerbReport(const std::string& verb, const std::string& staging_dir, int max_depth = 0);

}  // namespace skycal::cli
