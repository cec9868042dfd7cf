#pragma once
// Non-negative least squares (Lawson & Hanson 1974, "Solving Least Squares Problems", ch. 23):
// min ||A x - b|| subject to x >= 0. The cost-model fit needs it because a negative
// nanoseconds-per-unit would make more work faster.

#include <Eigen/Core>

namespace enavi::board {

struct NnlsResult {
  Eigen::VectorXd x;
  int iterations = 0;
  bool converged = false;
};

/// @pre A.rows() == b.size()
NnlsResult SolveNnls(const Eigen::MatrixXd& A, const Eigen::VectorXd& b, int max_iterations = 0);

}  // namespace enavi::board
