// Byte reader shared by the fuzz harnesses: turns the fuzzer's bytes into typed values, and
// returns zeros once the bytes run out (so every input is a valid, finite-length program).
// No clang header needed: the harnesses also build with g++ as corpus-replay gtests.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <string>

namespace pbc_fuzz
{
class Input
{
public:
  Input(const std::uint8_t* data, std::size_t size) : data_(data), size_(size)
  {
  }

  bool empty() const
  {
    return pos_ >= size_;
  }
  std::size_t remaining() const
  {
    return pos_ < size_ ? size_ - pos_ : 0;
  }

  std::uint8_t byte()
  {
    return pos_ < size_ ? data_[pos_++] : 0;
  }
  std::uint16_t u16()
  {
    return static_cast<std::uint16_t>(byte() | (byte() << 8));
  }
  std::uint32_t u32()
  {
    return static_cast<std::uint32_t>(u16()) | (static_cast<std::uint32_t>(u16()) << 16);
  }
  bool flag()
  {
    return (byte() & 1) != 0;
  }

  /// Any bit pattern: NaN, Inf, subnormal, huge, negative zero.
  double rawDouble()
  {
    std::uint8_t bytes[8] = {};
    for (auto& b : bytes)
    {
      b = byte();
    }
    double v;
    std::memcpy(&v, bytes, sizeof v);
    return v;
  }

  /// In [lo, hi], 16 bits of resolution.
  double range(double lo, double hi)
  {
    return lo + (hi - lo) * (u16() / 65535.0);
  }

  /// Mostly plausible values around `typical` (scale `scale`), sometimes an extreme one.
  double value(double typical, double scale)
  {
    switch (byte() % 8)
    {
      case 0:
        return rawDouble();
      case 1:
      {
        static const double kSpecial[] = { std::numeric_limits<double>::quiet_NaN(),
                                           std::numeric_limits<double>::infinity(),
                                           -std::numeric_limits<double>::infinity(),
                                           std::numeric_limits<double>::max(),
                                           -std::numeric_limits<double>::max(),
                                           std::numeric_limits<double>::denorm_min(),
                                           0.0,
                                           -0.0,
                                           1e300,
                                           -1e300,
                                           1e15,
                                           1e-300 };
        return kSpecial[byte() % (sizeof kSpecial / sizeof kSpecial[0])];
      }
      default:
        return typical + scale * range(-1.0, 1.0);
    }
  }

  std::string text(std::size_t max_length)
  {
    std::string s;
    const std::size_t n = byte() % (max_length + 1);
    for (std::size_t i = 0; i < n && !empty(); ++i)
    {
      s.push_back(static_cast<char>(byte()));
    }
    return s;
  }

  /// The rest of the input.
  std::string rest()
  {
    std::string s(reinterpret_cast<const char*>(data_ + pos_), remaining());
    pos_ = size_;
    return s;
  }

private:
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t pos_ = 0;
};

/// Stops the process with a message: libFuzzer and the replay test both see it as a crash.
[[noreturn]] inline void fail(const std::string& what)
{
  std::fprintf(stderr, "FUZZ FAILURE: %s\n", what.c_str());
  std::fflush(stderr);
  std::abort();
}
}  // namespace pbc_fuzz
