// Stability scan of paper mode's comb loop (Eq. 3/6 and 5/7 have the same form) against the
// period L in samples, over the gains validate() accepts (docs/reliability.md, F5). Not a test:
// a measurement behind kMinPaperPeriod, run by hand:
//   g++ -O2 test/fuzz/paper_loop_scan.cpp -o /tmp/paper_loop_scan && /tmp/paper_loop_scan 2 40
// The homogeneous loop (no input): v_n = v_{n-1} - (beta * midrange(v_{n-1..n-L}) +
// alpha * (v_{n-1} - v_{n-L})) / L, from random and alternating starts; prints, per L, the largest
// growth of max|v| over 300 L + 3000 steps, over alpha 0..1.95 (step 0.05) and beta 0..12 (0.1).
// A growth above 1 is a divergence (with beta = 0 a constant stays: growth 1).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <vector>

namespace
{
double growth(double alpha, double beta, int period, int seed)
{
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal;
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  std::vector<double> v;
  for (int i = 0; i < period; ++i)
    v.push_back(seed % 2 ? normal(rng) : (i % 2 ? 1.0 : -1.0) * uniform(rng));
  auto largest = [&] {
    double m = 0.0;
    for (std::size_t k = v.size() - period; k < v.size(); ++k)
      m = std::max(m, std::abs(v[k]));
    return m;
  };
  const double start = largest();
  for (int n = 0; n < 300 * period + 3000; ++n)
  {
    const auto last = v.end() - period;
    const auto [lo, hi] = std::minmax_element(last, v.end());
    const double d = beta * 0.5 * (*lo + *hi) + alpha * (v.back() - *last);
    v.push_back(v.back() - d / period);
    if (static_cast<int>(v.size()) > 4 * period)
      v.erase(v.begin(), v.end() - period);
  }
  return largest() / start;
}
}  // namespace

int main(int argc, char** argv)
{
  const int first = argc > 1 ? std::atoi(argv[1]) : 2;
  const int last = argc > 2 ? std::atoi(argv[2]) : 12;
  for (int period = first; period <= last; ++period)
  {
    double worst = 0.0, worst_alpha = 0.0, worst_beta = 0.0;
    for (int a = 0; a < 40; ++a)
      for (int b = 0; b <= 120; ++b)
        for (int seed = 0; seed < 6; ++seed)
        {
          const double g = growth(0.05 * a, 0.1 * b, period, seed);
          if (g > worst)
          {
            worst = g;
            worst_alpha = 0.05 * a;
            worst_beta = 0.1 * b;
          }
        }
    std::printf("L = %3d: largest growth %.3g (alpha %.2f, beta %.1f)\n", period, worst, worst_alpha, worst_beta);
    std::fflush(stdout);
  }
  return 0;
}
