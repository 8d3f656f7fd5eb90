// What a single-file output may replace, and the names it may have: a verb never writes
// over a file of another kind or a page it did not write, and never writes one format under
// another format's extension. AtomicOutput and the EXR, JSON and PNG writers ask here.
#pragma once
#include <string>
#include <vector>

namespace skycal {

// A single-file output replaces an existing file only when it is of the kind the name
// promises and, for HTML, one skycal wrote: `.exr` must start with OpenEXR's magic number,
// `.png` with PNG's signature, `.json` with '{' or '[', `.html`/`.htm` must carry the line
// skycal's report writes ("Written by skycal"). Anything else at that path (a user's CSV
// renamed, a FIFO, a device) is refused; a path that does not exist, and names with other
// extensions, pass. AtomicOutput asks this for every file it writes. Throws skycal::Error
// naming the path and what was found.
void RefuseReplacingAnotherKind(const std::string& path);

// A preset's LUT table (an EXR with attribute skycalLut) is replaced only by another LUT:
// an image written over it would leave a preset that no longer loads. The EXR writer asks
// this for images; outputs staged elsewhere first (AtomicOutputGroup) ask it for their
// destination. Throws skycal::Error naming the path and the LUT.
void RefuseReplacingAPresetLut(const std::string& path);

// Throws when `path` ends in the extension of another format than `extension` (".exr",
// ".json", ".png"): EXR bytes in `w.png` or JSON in `notes.csv` would be unreadable to the
// tool the name suggests, and the user's file of that name would be gone. Names with no
// extension skycal knows (scratch names, ".tmp-PID") pass. `what` names the format.
void RefuseMismatchedExtension(const std::string& path, const std::string& extension, const std::string& what);

// Throws unless `path` ends in one of `extensions` (lower case, with the dot, compared
// case-insensitively): `role` names the option for the message, `what` the format written.
void RequireExtension(const std::string& role, const std::string& path, const std::vector<std::string>& extensions,
                      const std::string& what);

}  // namespace skycal
