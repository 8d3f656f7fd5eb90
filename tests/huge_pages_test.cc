// The re-exec that asks glibc for huge pages (core/huge_pages.h): set only where the kernel
// gives them on request, appended to the user's tunables, never twice (an exec loop).
#include <gtest/gtest.h>

#include <string>

#include "skycal/core/huge_pages.h"

namespace skycal {
namespace {

TEST(HugePages, TheTunableIsAddedOnlyWhereTheKernelWantsARequest) {
  EXPECT_EQ(HugePageTunables(nullptr, "madvise"), "glibc.malloc.hugetlb=1");
  EXPECT_EQ(HugePageTunables("", "madvise"), "glibc.malloc.hugetlb=1");
  EXPECT_EQ(HugePageTunables("glibc.malloc.arena_max=2", "madvise"), "glibc.malloc.arena_max=2:glibc.malloc.hugetlb=1");
  EXPECT_EQ(HugePageTunables(nullptr, "always"), "");  // huge pages without asking
  EXPECT_EQ(HugePageTunables(nullptr, "never"), "");
  EXPECT_EQ(HugePageTunables(nullptr, ""), "");        // no transparent huge pages at all
}

// The second start sees the tunable and goes on: no loop, and a user's own choice stands.
TEST(HugePages, ATunableAlreadySetIsLeftAlone) {
  EXPECT_EQ(HugePageTunables("glibc.malloc.hugetlb=1", "madvise"), "");
  EXPECT_EQ(HugePageTunables("glibc.malloc.hugetlb=0", "madvise"), "");
  EXPECT_EQ(HugePageTunables("glibc.malloc.arena_max=2:glibc.malloc.hugetlb=2", "madvise"), "");
}

}  // namespace
}  // namespace skycal
