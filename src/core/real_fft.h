// A real-to-complex FFTW transform of one size, planned once (internal to the core library).
#pragma once

#include <fftw3.h>

#include <functional>
#include <mutex>
#include <vector>

namespace periodic_bias_compensation
{
/// Smallest 2^a 3^b 5^c >= n: FFTW is fastest on such sizes (a window of 87.7 Hz x 30 s =
/// 2631 = 3 x 877 samples would need a prime-size transform).
int fastFftSize(int n);

/// The periodic Hann window of n samples, 0.5 - 0.5 cos(2 pi i / n), and in *power (if given)
/// the sum of its squares.
std::vector<double> hannWindow(int n, double* power = nullptr);

/// Runs `task` on the core's background planning thread (one per process, at nice 19, so that it
/// leaves the core to the threads that feed samples), in the order given. FFTW plans a transform
/// size it has not seen in milliseconds: that is done there, not in a sample's call.
void planInBackground(std::function<void()> task);

/// Plans and drops transforms of these sizes. FFTW keeps what it planned: a transform of one of
/// them is then planned in microseconds instead of milliseconds.
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
    fftw_execute(plan_);
  }
  void inverse()
  {
    fftw_execute(inverse_plan_);
  }
  double power(int k) const
  {
    return out[k][0] * out[k][0] + out[k][1] * out[k][1];
  }

  double* in;
  fftw_complex* out;

private:
  int n_;
  fftw_plan plan_;
  fftw_plan inverse_plan_;
};

}  // namespace periodic_bias_compensation
