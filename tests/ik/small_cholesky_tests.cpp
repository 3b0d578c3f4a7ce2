// The per-level kernels of the fast path (ik/small_cholesky.h) against Eigen's own
// decompositions, on the sizes the solver meets (2 to 24 rows).
#include <catch2/catch.hpp>

#include <random>

#include <Eigen/LU>
#include <Eigen/QR>

#include "ik/small_cholesky.h"

using namespace embody;
using namespace embody::ik;

namespace {

Eigen::MatrixXd randomMatrix(int rows, int cols, std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::MatrixXd m(rows, cols);
  for (int j = 0; j < cols; ++j)
    for (int i = 0; i < rows; ++i) m(i, j) = n(rng);
  return m;
}

}  // namespace

TEST_CASE("small Cholesky: factor, solves, right solve and inverse match Eigen", "[ik]") {
  std::mt19937 rng(11);
  for (int m : {1, 2, 3, 6, 12, 24}) {
    const Eigen::MatrixXd j = randomMatrix(m, m + 7, rng);
    const Eigen::MatrixXd g = j * j.transpose();
    Eigen::MatrixXd l = g;
    Eigen::VectorXd inv(m);
    REQUIRE(detail::choleskyInPlace(l, inv));
    const Eigen::MatrixXd lower = l.triangularView<Eigen::Lower>();
    CHECK((lower * lower.transpose() - g).norm() < 1e-10 * g.norm());
    CHECK((inv.cwiseProduct(lower.diagonal()) - Eigen::VectorXd::Ones(m)).norm() < 1e-14 * m);

    const Eigen::VectorXd b = randomMatrix(m, 1, rng);
    Eigen::VectorXd x = b;
    detail::choleskySolve(l, inv, x.data());
    CHECK((g * x - b).norm() < 1e-8 * b.norm() * g.norm() * (g.inverse()).norm());

    Eigen::MatrixXd rhs = randomMatrix(9, m, rng);  // B L⁻ᵀ
    const Eigen::MatrixXd expected = lower.triangularView<Eigen::Lower>().solve(rhs.transpose()).transpose();
    detail::solveRightLowerTransposed(l, inv, rhs);
    CHECK((rhs - expected).norm() < 1e-9 * expected.norm());

    Eigen::MatrixXd scratch(m, m), inverse(m, m);
    detail::choleskyInverse(l, inv, scratch, inverse);
    CHECK((inverse * g - Eigen::MatrixXd::Identity(m, m)).norm() < 1e-7);
  }
}

TEST_CASE("small Cholesky: a matrix that is not positive definite is refused", "[ik]") {
  Eigen::MatrixXd g = Eigen::MatrixXd::Identity(4, 4);
  g(2, 2) = -1e-3;
  Eigen::VectorXd inv(4);
  Eigen::MatrixXd l = g;
  CHECK_FALSE(detail::choleskyInPlace(l, inv));
  l = g;
  l(2, 2) = std::numeric_limits<double>::quiet_NaN();
  CHECK_FALSE(detail::choleskyInPlace(l, inv));
}

TEST_CASE("pivoted Cholesky finds the rank and rows that span a rank-deficient Jacobian's row space", "[ik]") {
  std::mt19937 rng(12);
  for (const auto& [m, rank] : std::vector<std::pair<int, int>>{{6, 3}, {12, 7}, {24, 15}, {24, 24}, {5, 0}}) {
    // J = A B: m rows of rank `rank` in 40 columns.
    Eigen::MatrixXd j = Eigen::MatrixXd::Zero(m, 40);
    if (rank > 0) j = randomMatrix(m, rank, rng) * randomMatrix(rank, 40, rng);
    const Eigen::MatrixXd g = j * j.transpose();
    Eigen::MatrixXd work(m, m);
    Eigen::VectorXi perm(m);
    Eigen::VectorXd inv(m);
    const int found = detail::pivotedCholesky(g, 1e-12, m, work, perm, inv);
    INFO("m " << m << " rank " << rank);
    REQUIRE(found == rank);
    if (rank == 0) continue;
    Eigen::MatrixXd gi(rank, rank);
    for (int a = 0; a < rank; ++a)
      for (int b = 0; b < rank; ++b) gi(a, b) = g(perm(a), perm(b));
    const Eigen::MatrixXd lower = work.topLeftCorner(rank, rank).triangularView<Eigen::Lower>();
    CHECK((lower * lower.transpose() - gi).norm() < 1e-9 * g.norm());
    // U = J_Iᵀ L⁻ᵀ is orthonormal and spans J's row space: U Uᵀ is J's row-space projector.
    Eigen::MatrixXd ji(rank, 40);
    for (int a = 0; a < rank; ++a) ji.row(a) = j.row(perm(a));
    const Eigen::MatrixXd u = lower.triangularView<Eigen::Lower>().solve(ji).transpose();
    CHECK((u.transpose() * u - Eigen::MatrixXd::Identity(rank, rank)).norm() < 1e-8);
    const Eigen::MatrixXd projector = j.completeOrthogonalDecomposition().pseudoInverse() * j;
    CHECK((u * u.transpose() - projector).norm() < 1e-8);
  }
  // max_rank caps the factorisation.
  const Eigen::MatrixXd j = randomMatrix(8, 20, rng);
  Eigen::MatrixXd work(8, 8);
  Eigen::VectorXi perm(8);
  Eigen::VectorXd inv(8);
  CHECK(detail::pivotedCholesky(j * j.transpose(), 1e-12, 5, work, perm, inv) == 5);
}
