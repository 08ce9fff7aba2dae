// A real-to-complex FFTW transform of one size, planned once (internal to the core library).
#pragma once

#include <fftw3.h>

#include <mutex>
#include <vector>

#include "background.h"

namespace periodic_bias_compensation
{
/// Smallest 2^a 3^b 5^c >= n: FFTW is fastest on such sizes (a window of 87.7 Hz x 30 s =
/// 2631 = 3 x 877 samples would need a prime-size transform).
int fastFftSize(int n);

/// The periodic Hann window of n samples, 0.5 - 0.5 cos(2 pi i / n), and in *power (if given)
/// the sum of its squares.
std::vector<double> hannWindow(int n, double* power = nullptr);

/// Plans transforms of these sizes: a RealFft of one of them then takes the plans made (a size
/// not seen before is planned in milliseconds, under the planner's lock).
void warmFftPlans(const std::vector<int>& sizes);

/// The input `in` (n values) transformed into `out` (n / 2 + 1 bins) by execute(); `out` (the
/// non-negative frequencies of a Hermitian spectrum) back into `in` by inverse(), unnormalised:
/// in[j] = sum over all n bins of X_k exp(+2 pi i j k / n). inverse() overwrites `out`.
class RealFft
{
public:
  explicit RealFft(int n);
  ~RealFft();
  RealFft(const RealFft&) = delete;
  RealFft& operator=(const RealFft&) = delete;

  int size() const
  {
    return n_;
  }
  /// Executing an existing plan is thread-safe in FFTW; planning is not and is serialised here.
  void execute()
  {
    fftw_execute_dft_r2c(plan_, in, out);
  }
  void inverse()
  {
    fftw_execute_dft_c2r(inverse_plan_, out, in);
  }
  double power(int k) const
  {
    return out[k][0] * out[k][0] + out[k][1] * out[k][1];
  }

  double* in;
  fftw_complex* out;

private:
  int n_;
  fftw_plan plan_;  ///< the process's plans of this size, shared (never destroyed)
  fftw_plan inverse_plan_;
};

}  // namespace periodic_bias_compensation
