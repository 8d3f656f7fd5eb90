// Large buffers in 2 MB pages. A calibration touches a few hundred MB of fresh memory (the
// cloud noise and its packed views on the device, frames and their copies); where each 4 KB
// page costs a fault (several microseconds in a virtual machine), that is a second of a
// five-second command (bench/results/calibrate.md). glibc's malloc asks the kernel for
// transparent huge pages when GLIBC_TUNABLES holds glibc.malloc.hugetlb=1 (glibc 2.35+),
// and reads it at start-up only.
#pragma once
#include <string>

namespace skycal {

// Where the kernel gives huge pages only on request (/sys/kernel/mm/transparent_hugepage/
// enabled is "madvise", Debian's default) and the tunable is not set, re-executes this
// binary (/proc/self/exe) once with it added to GLIBC_TUNABLES, arguments and the rest of
// the environment unchanged. Returns when that does not apply, when SKYCAL_HUGE_PAGES=0,
// or when the exec fails (the process goes on as it is). Call first in main, before any
// thread or handler, for work that touches enough memory to repay a second start.
void ReexecWithHugePages(char** argv);

// What ReexecWithHugePages sets GLIBC_TUNABLES to, given its current value (null: unset) and
// the kernel's transparent huge page mode ("always", "madvise", "never", "": none); "" when
// it does not re-execute.
std::string HugePageTunables(const char* tunables, const std::string& thp_mode);

}  // namespace skycal
