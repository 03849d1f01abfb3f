// The viewer's render, build and comparison threads yield the CPU to the UI thread: each lowers its
// own scheduling priority when it starts (nice +10 on Linux, where the nice value is per thread and
// the threads they start, TBB's workers among them, inherit it). Rendering keeps every core while
// the UI is idle, and a key press or a drag is handled at once when it is not, on 2 cores as on 64.
#pragma once

#if defined(__linux__)
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>
#endif

namespace candela {

inline constexpr int kBackgroundNice = 10;

inline void lowerThisThreadsPriority() {
#if defined(__linux__)
  // Raising one's own nice value needs no privilege; a failure leaves the thread as it was.
  const id_t tid = static_cast<id_t>(syscall(SYS_gettid));
  const int current = getpriority(PRIO_PROCESS, tid);
  if (current < kBackgroundNice) setpriority(PRIO_PROCESS, tid, kBackgroundNice);
#endif
}

}  // namespace candela
