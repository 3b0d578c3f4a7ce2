// The reference priority pass: plain n x n projectors and a JacobiSVD per level, exactly as
// pik.md writes it. Slow; what the fast pass is tested against.
#include <Eigen/SVD>

#include "ik/solver_detail.h"
#include "ik/solver_internal.h"

namespace embody::ik::detail {

void referencePass(const Model& model, Workspace& w, const SolveOptions& o) {
  w.dq = w.dq0;
  w.projector = w.projector0;
  w.level_step_reduced = false;
  std::fill(w.level_step_set.begin(), w.level_step_set.end(), 0);
  for (size_t k = 0; k < model.levels.size(); ++k) {
    const Model::Level& level = model.levels[k];
    if (!levelActive(level, w)) continue;
    const int m = level.rows;
    const auto j = w.jacobian.middleRows(level.first_row, m);
    Eigen::VectorXd& res = w.level_res[k];
    res = w.error.segment(level.first_row, m);
    res.noalias() -= j * w.dq;
    Eigen::MatrixXd& jh = w.level_j[k];
    jh.noalias() = j * w.projector;
    Eigen::MatrixXd& gram = w.level_gram[k];
    gram.noalias() = jh * jh.transpose();
    const double lambda2 = levelDamping(gram, w, k, o).lambda2;
    auto& svd = w.level_svd[k];
    svd.compute(jh);
    const auto& sv = svd.singularValues();
    Eigen::VectorXd& coef = w.level_y[k];
    const int p = static_cast<int>(sv.size());
    coef.head(p).noalias() = svd.matrixU().transpose() * res;
    for (int i = 0; i < p; ++i) {
      const double sigma = sv(i);
      const double denom = sigma * sigma + lambda2;
      // λ = 0 (damping_max = 0) drops the rank-deficient directions as the projector does.
      const bool kept = lambda2 > 0 || sigma > o.rank_tolerance;
      coef(i) = kept && denom > 0 ? coef(i) * sigma / denom : 0.0;
    }
    if (const double cap = levelStepScale(coef.head(p).norm(), o); cap < 1.0) coef.head(p) *= cap;  // |V c| = |c|
    Eigen::VectorXd& contribution = w.level_step[k];
    contribution.noalias() = svd.matrixV() * coef.head(p);
    w.level_step_set[k] = 1;
    w.dq += contribution;
    for (int i = 0; i < p; ++i)
      if (sv(i) > o.rank_tolerance) w.projector.noalias() -= svd.matrixV().col(i) * svd.matrixV().col(i).transpose();
  }
}

}  // namespace embody::ik::detail
