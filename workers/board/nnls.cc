#include "workers/board/nnls.h"

#include <limits>
#include <stdexcept>

#include <Eigen/Dense>

namespace enavi::board {
namespace {

// Least squares on the passive columns only; the others stay 0.
Eigen::VectorXd SolvePassive(const Eigen::MatrixXd& A, const Eigen::VectorXd& b,
                             const std::vector<bool>& passive) {
  std::vector<int> cols;
  for (int j = 0; j < static_cast<int>(passive.size()); ++j)
    if (passive[j]) cols.push_back(j);
  Eigen::VectorXd z = Eigen::VectorXd::Zero(A.cols());
  if (cols.empty()) return z;
  Eigen::MatrixXd Ap(A.rows(), cols.size());
  for (std::size_t k = 0; k < cols.size(); ++k) Ap.col(k) = A.col(cols[k]);
  const Eigen::VectorXd zp = Ap.colPivHouseholderQr().solve(b);
  for (std::size_t k = 0; k < cols.size(); ++k) z[cols[k]] = zp[k];
  return z;
}

}  // namespace

NnlsResult SolveNnls(const Eigen::MatrixXd& A, const Eigen::VectorXd& b, int max_iterations) {
  if (A.rows() != b.size()) throw std::logic_error("SolveNnls: A and b disagree in size");
  const int n = static_cast<int>(A.cols());
  if (max_iterations <= 0) max_iterations = 3 * n + 10;
  const double tol = 1e-12 * std::max(1.0, A.norm() * b.norm());
  NnlsResult r;
  r.x = Eigen::VectorXd::Zero(n);
  std::vector<bool> passive(n, false);
  while (r.iterations < max_iterations) {
    // Gradient of the objective's negative: where increasing a zero variable helps most.
    const Eigen::VectorXd w = A.transpose() * (b - A * r.x);
    int best = -1;
    double best_w = tol;
    for (int j = 0; j < n; ++j)
      if (!passive[j] && w[j] > best_w) best = j, best_w = w[j];
    if (best < 0) {
      r.converged = true;
      return r;
    }
    passive[best] = true;
    ++r.iterations;
    // Inner loop: step towards the unconstrained solution of the passive set, stopping where a
    // variable would turn negative, and drop it from the set.
    while (true) {
      const Eigen::VectorXd z = SolvePassive(A, b, passive);
      bool feasible = true;
      for (int j = 0; j < n; ++j) feasible &= !passive[j] || z[j] > 0;
      if (feasible) {
        r.x = z;
        break;
      }
      double alpha = std::numeric_limits<double>::infinity();
      for (int j = 0; j < n; ++j)
        if (passive[j] && z[j] <= 0) alpha = std::min(alpha, r.x[j] / (r.x[j] - z[j]));
      r.x += alpha * (z - r.x);
      for (int j = 0; j < n; ++j)
        if (passive[j] && r.x[j] <= 1e-15) passive[j] = false, r.x[j] = 0;
    }
  }
  return r;
}

}  // namespace enavi::board
