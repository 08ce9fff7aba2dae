// The shared numeric helpers: angle wrapping, the median and the in-place upper median, the
// polynomial sine and cosine; the zeroed buffer.
#include <gtest/gtest.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <tuple>
#include <utility>
#include <vector>

#include "periodic_bias_compensation/common/numeric.h"
#include "periodic_bias_compensation/core/zeroed_buffer.h"

namespace pbc = periodic_bias_compensation;

TEST(Numeric, WrapAngleKeepsTheAngleWithinPlusMinusPi)
{
  EXPECT_DOUBLE_EQ(pbc::wrapAngle(0.5), 0.5);
  EXPECT_NEAR(pbc::wrapAngle(0.5 + 6.0 * M_PI), 0.5, 1e-12);
  EXPECT_NEAR(pbc::wrapAngle(-0.5 - 4.0 * M_PI), -0.5, 1e-12);
  EXPECT_NEAR(pbc::wrapAngle(3.5), 3.5 - 2.0 * M_PI, 1e-15);
  EXPECT_NEAR(pbc::wrapAngle(-3.5), 2.0 * M_PI - 3.5, 1e-15);
  for (double a = -50.0; a <= 50.0; a += 0.37)
  {
    const double w = pbc::wrapAngle(a);
    EXPECT_LE(std::abs(w), M_PI) << a;
    EXPECT_NEAR(std::remainder(a - w, 2.0 * M_PI), 0.0, 1e-12) << a;
  }
}

TEST(Numeric, MedianAveragesTheTwoMiddleValuesOfAnEvenCount)
{
  EXPECT_DOUBLE_EQ(pbc::median({ 5.0, 1.0, 3.0 }), 3.0);
  EXPECT_DOUBLE_EQ(pbc::median({ 4.0, 1.0, 3.0, 2.0 }), 2.5);
  EXPECT_DOUBLE_EQ(pbc::median({ 7.0 }), 7.0);
  EXPECT_TRUE(std::isnan(pbc::median({})));
}

TEST(Numeric, UpperMedianIsTheElementOfRankHalfTheCount)
{
  std::vector<double> odd{ 9.0, 2.0, 7.0, 4.0, 5.0 };
  EXPECT_DOUBLE_EQ(pbc::upperMedian(odd.begin(), odd.end()), 5.0);
  std::vector<double> even{ 4.0, 1.0, 3.0, 2.0 };
  EXPECT_DOUBLE_EQ(pbc::upperMedian(even.begin(), even.end()), 3.0);
  // In place: the range is reordered around its middle, nothing is allocated.
  EXPECT_LE(even[0], 3.0);
  EXPECT_LE(even[1], 3.0);
  EXPECT_DOUBLE_EQ(even[2], 3.0);
}

TEST(Numeric, SinCosTurnIsTheLibrarysToAnUlpOrTwo)
{
  // Every quadrant and its edges, the turn's ends and the points between.
  double worst = 0.0;
  for (int i = 0; i <= 400000; ++i)
  {
    const double u = i / 400000.0;
    double s, c;
    pbc::sinCosTurn(u, &s, &c);
    const long double a = 2.0L * M_PIl * u;  // the reference in extended precision
    worst = std::max(
        { worst, static_cast<double>(std::abs(s - std::sin(a))), static_cast<double>(std::abs(c - std::cos(a))) });
  }
  EXPECT_LT(worst, 2.3e-16);  // two units in the last place of 1
  double s, c;
  pbc::sinCosTurn(0.0, &s, &c);
  EXPECT_EQ(s, 0.0);
  EXPECT_EQ(c, 1.0);
  pbc::sinCosTurn(0.25, &s, &c);
  EXPECT_EQ(s, 1.0);
  EXPECT_NEAR(c, 0.0, 1e-16);
}

TEST(Numeric, SinCosOfAnyAngleIsWithinItsBound)
{
  for (double x = -40.0; x <= 40.0; x += 0.0137)
  {
    double s, c;
    pbc::sinCos(x, &s, &c);
    const double bound = (2.0 + std::abs(x)) * 2.3e-16;  // the turn x / 2 pi is rounded
    EXPECT_NEAR(s, static_cast<double>(std::sin(static_cast<long double>(x))), bound) << x;
    EXPECT_NEAR(c, static_cast<double>(std::cos(static_cast<long double>(x))), bound) << x;
  }
}

namespace
{
/// Pages of `buffer` in memory (mincore), of those it spans.
std::pair<int, int> residentPages(const pbc::ZeroedBuffer& buffer)
{
  const std::size_t page = static_cast<std::size_t>(sysconf(_SC_PAGESIZE));
  const auto begin = reinterpret_cast<std::uintptr_t>(buffer.data()) / page * page;
  const auto end = reinterpret_cast<std::uintptr_t>(buffer.data() + buffer.size());
  std::vector<unsigned char> in_core((end - begin + page - 1) / page);
  if (mincore(reinterpret_cast<void*>(begin), end - begin, in_core.data()) != 0)
    return { -1, -1 };
  int resident = 0;
  for (unsigned char c : in_core)
    resident += c & 1;
  return { resident, static_cast<int>(in_core.size()) };
}
}  // namespace

TEST(ZeroedBuffer, HoldsZerosCopiesAndMoves)
{
  for (std::size_t n : { std::size_t{ 0 }, std::size_t{ 7 }, std::size_t{ 1 } << 20 })
  {
    pbc::ZeroedBuffer buffer(n);
    ASSERT_EQ(buffer.size(), n);
    EXPECT_EQ(buffer.empty(), n == 0);
    bool zero = true;
    for (std::size_t i = 0; i < n; ++i)
      zero = zero && buffer[i] == 0.0;
    EXPECT_TRUE(zero) << n;
    if (n == 0)
      continue;
    buffer[n - 1] = 2.5;
    pbc::ZeroedBuffer copy(buffer);
    copy[0] = -1.0;
    EXPECT_EQ(copy[n - 1], 2.5);
    EXPECT_EQ(buffer[0], 0.0) << "the copy shares no memory";
    pbc::ZeroedBuffer moved(std::move(copy));
    EXPECT_TRUE(copy.empty());
    EXPECT_EQ(moved[0], -1.0);
    buffer = moved;
    EXPECT_EQ(buffer[0], -1.0);
    buffer = pbc::ZeroedBuffer(3);
    EXPECT_EQ(buffer.size(), 3u);
    EXPECT_EQ(buffer[2], 0.0);
  }
}

// Sizing a buffer for a high sample rate costs no time in the call that sizes it: a large
// buffer's pages are not in memory until written, and then only those written.
TEST(ZeroedBuffer, ALargeBuffersPagesComeInAsTheyAreWritten)
{
  pbc::ZeroedBuffer buffer(std::size_t{ 4 } << 20);  // 32 MB, as at 2.8 kHz
  auto [resident, pages] = residentPages(buffer);
  ASSERT_GT(pages, 1000);
  EXPECT_LE(resident, 2) << "of " << pages << " pages";
  const double sum = buffer[0] + buffer[buffer.size() / 2] + buffer[buffer.size() - 1];
  EXPECT_EQ(sum, 0.0);
  for (std::size_t i = 0; i < buffer.size() / 4; ++i)
    buffer[i] = 1.0;
  std::tie(resident, pages) = residentPages(buffer);
  EXPECT_GE(resident, pages / 4 - 1);
  EXPECT_LE(resident, pages / 4 + 4);
}
