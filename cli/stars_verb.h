// `skycal stars`: remove the stars of a night frame (capture/star_removal.h): small isolated
// point sources replaced by their neighbourhood's median, counted, and masked.
#pragma once
#include <string>

#include <nlohmann/json.hpp>

#include "skycal/capture/star_removal.h"

namespace skycal::cli {

class VerbCommandLine;

struct StarsOptions {
  std::string reference;   // the frame (*.exr)
  std::string out;         // the cleaned frame (*.exr): every channel and attribute of the input kept
  std::string mask_out;    // optional (*.exr): R = G = B = 1 where a star was replaced
  capture::StarRemovalOptions removal;
  bool IsValid(std::string* why) const;
};

// Writes atomically (both files or neither) and returns the summary; throws skycal::Error.
nlohmann::json RunStarsImpl(const StarsOptions& options);
StarsOptions ParseStarsArgs(int argc, char** argv);
int RunStars(int argc, char** argv);
// The removal options' flags (shared with capture --remove-stars).
void RegisterStarOptions(VerbCommandLine& cl, capture::StarRemovalOptions* o);
// `message` with StarRemovalOptions' fields written as the flags RegisterStarOptions registers.
std::string WithStarFlags(const std::string& message);

}  // namespace skycal::cli
