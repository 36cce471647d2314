// SPDX-License-Identifier: MIT
// Positive control of proof.core_symbols: code the flight rules forbid (a std::vector and a
// dynamic Eigen matrix), compiled with exactly the core's flags. The symbol check must reject
// this library; if it ever passes, the check has gone blind.
#include <vector>

#include <Eigen/Core>

extern "C" double sfd_canary_heap(int n) {
    std::vector<double> v(static_cast<std::size_t>(n), 1.0);
    Eigen::MatrixXd m = Eigen::MatrixXd::Ones(n, n);
    return v.back() + m.sum();
}
