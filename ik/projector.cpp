#include "ik/projector.h"

namespace embody::ik {

Eigen::MatrixXd incrementalNullspaceProjector(const Eigen::MatrixXd& rows, double tolerance,
                                              std::vector<int>* dependent) {
  const Eigen::Index n = rows.cols();
  Eigen::MatrixXd p = Eigen::MatrixXd::Identity(n, n);
  Eigen::VectorXd u(n);
  for (Eigen::Index i = 0; i < rows.rows(); ++i) {
    u.noalias() = p * rows.row(i).transpose();
    if (u.norm() > tolerance * rows.row(i).norm()) {
      p.noalias() -= u * u.transpose() / u.squaredNorm();
    } else if (dependent) {
      dependent->push_back(static_cast<int>(i));
    }
  }
  return p;
}

}  // namespace embody::ik
