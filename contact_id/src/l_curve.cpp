// The L-curve of the regularised geometric identification over λ: l_curve.
#include <hil/contact_id/identification.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace hil::contact_id {

LCurve l_curve(const ContactProblem& p, const GeometricOptions& base, double lo, double hi, int n) {
  if (!(lo > 0.0 && hi > lo && n >= 3)) throw std::invalid_argument("L-curve needs 0 < lo < hi and at least 3 values");
  LCurve c;
  GeometricOptions o = base;
  Eigen::VectorXd x = p.scene().design();
  for (int i = n - 1; i >= 0; --i) {
    const double t = std::log(lo) + (std::log(hi) - std::log(lo)) * i / (n - 1);
    o.lambda = std::exp(t);
    const auto g = identify_geometry(p, o, &x);
    x = g.x;
    c.lambda.push_back(o.lambda);
    c.force_cost.push_back(g.force_cost);
    c.geometric_cost.push_back(g.geometric_cost);
    c.x.push_back(g.x);
  }
  // Ascending λ.
  std::reverse(c.lambda.begin(), c.lambda.end());
  std::reverse(c.force_cost.begin(), c.force_cost.end());
  std::reverse(c.geometric_cost.begin(), c.geometric_cost.end());
  std::reverse(c.x.begin(), c.x.end());
  const auto N = c.lambda.size();
  c.curvature.assign(N, 0.0);
  double gfloor = 1e-300;
  for (double g : c.geometric_cost) gfloor = std::max(gfloor, g * 1e-12);
  std::vector<double> X(N), Y(N), T(N);
  for (std::size_t i = 0; i < N; ++i) {
    X[i] = std::log(std::max(c.force_cost[i], 1e-300));
    Y[i] = std::log(std::max(c.geometric_cost[i], gfloor));
    T[i] = std::log(c.lambda[i]);
  }
  double best = -std::numeric_limits<double>::infinity();
  c.corner = N / 2;
  for (std::size_t i = 1; i + 1 < N; ++i) {
    const double h1 = T[i] - T[i - 1], h2 = T[i + 1] - T[i];
    const double dx = (X[i + 1] - X[i - 1]) / (h1 + h2), dy = (Y[i + 1] - Y[i - 1]) / (h1 + h2);
    const double ddx = 2.0 * ((X[i + 1] - X[i]) / h2 - (X[i] - X[i - 1]) / h1) / (h1 + h2);
    const double ddy = 2.0 * ((Y[i + 1] - Y[i]) / h2 - (Y[i] - Y[i - 1]) / h1) / (h1 + h2);
    const double den = std::pow(dx * dx + dy * dy, 1.5);
    const double k = den > 0.0 ? (dx * ddy - dy * ddx) / den : 0.0;
    c.curvature[i] = k;
    if (k > best) {
      best = k;
      c.corner = i;
    }
  }
  return c;
}

}  // namespace hil::contact_id
