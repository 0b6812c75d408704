#pragma once
// Shared by the command-line tools (lodbake, loddump); not part of lodrt's API.
//
// Fresh pages are the dearest memory these tools touch: on the virtual machines we measure on, the
// first write to a 4 KB page costs 10-35 us (a fault the hypervisor serves too). A bake of
// dragon_poisson took ~240,000 such faults and `loddump` of its pack ~128,000, most of them in
// malloc's memory. glibc 2.35+ backs its heap and its mapped blocks with transparent huge pages under
// the tunable glibc.malloc.hugetlb=1, which it reads only at start-up, so a tool starts itself again
// (execv of /proc/self/exe, same arguments) with the tunable added to GLIBC_TUNABLES, unless
// GLIBC_TUNABLES already names it (the user's setting stands; =0 opts out). dragon_poisson: the bake
// 10.7 -> 8.4 s, `lodbake encode` 0.83 -> 0.65 s, `lodbake repair` 1.25 -> 0.89 s, `loddump` of the
// pack 2.28 -> 1.00 s, for a few MiB more peak resident size (docs/cli.md, "Memory").

#include <cstdlib>
#include <cstring>
#include <string>

#if defined(__linux__)
#include <unistd.h>
#endif

namespace lodtools {

/// Returns only if no restart happened or it failed (then the environment is as it was).
inline void restartWithHugePageHeap(char** argv) {
#if defined(__GLIBC__) && defined(__linux__)
    const char* found = std::getenv("GLIBC_TUNABLES");
    if (found != nullptr && std::strstr(found, "glibc.malloc.hugetlb") != nullptr) return;
    const bool had = found != nullptr;
    const std::string before = had ? found : "";
    const std::string value = before.empty() ? "glibc.malloc.hugetlb=1" : before + ":glibc.malloc.hugetlb=1";
    if (setenv("GLIBC_TUNABLES", value.c_str(), 1) != 0) return;
    execv("/proc/self/exe", argv);
    // Still here: the restart failed. Put the variable back so nothing this process starts sees it.
    if (had)
        setenv("GLIBC_TUNABLES", before.c_str(), 1);
    else
        unsetenv("GLIBC_TUNABLES");
#else
    (void)argv;
#endif
}

} // namespace lodtools
