// SPDX-License-Identifier: MIT
// Positive control of proof.stack_usage: a recursive function and a 20 KiB frame. The stack report
// must reject both; if it ever passes, the report has gone blind.
#include <cstddef>

namespace {
// Doubly recursive, so the compiler cannot turn it into a loop.
int canary_recurse(int n) {
    return n <= 1 ? n : canary_recurse(n - 1) + canary_recurse(n - 2);
}
}  // namespace

extern "C" double sfd_canary_stack(const double *in, int n) {
    volatile double big[2560];  // 20 KiB
    for (int i = 0; i < 2560; ++i) big[i] = in[static_cast<std::size_t>(i % (n > 0 ? n : 1))];
    return big[static_cast<std::size_t>(n) % 2560U] + canary_recurse(n & 15);
}
