#pragma once
// Null-space projectors of linear equality rows, built as pik.md's corrected Algorithm 1.
#include <Eigen/Core>

#include <vector>

namespace embody::ik {

// P0 = I - A⁺A built row by row: start with P = I; for each row c: u = P c; if |u| > tol |c|
// then P -= u uᵀ / |u|², else the row depends on earlier ones: skipped, its index appended to
// `dependent` (first added wins). A is g x n; returns n x n.
Eigen::MatrixXd incrementalNullspaceProjector(const Eigen::MatrixXd& rows, double tolerance = 1e-9,
                                              std::vector<int>* dependent = nullptr);

}  // namespace embody::ik
