// A buffer of doubles that starts at zero without writing them (estimation core, no ROS).
//
// Buffers sized for the sample rate once it is known hold tens of seconds of samples: at 2.8 kHz
// the spectral wave filter's histories and the paper loop's tables are about 30 MB. Filled with
// zeros in the call that sizes them, every page of that is faulted in and cleared there (85 ms
// at 2.8 kHz). A large ZeroedBuffer takes its pages from the kernel unmapped instead (they read
// as zero): each is faulted in when first written, spread over the samples that fill it.
#pragma once

#include <cstddef>

namespace periodic_bias_compensation
{
class ZeroedBuffer
{
public:
  /// Below this many bytes the buffer is allocated and cleared at once (a page mapping costs
  /// more than clearing it).
  static constexpr std::size_t kMappedBytes = 64 * 1024;

  ZeroedBuffer() = default;
  /// n values of zero; throws std::bad_alloc when the memory cannot be had.
  explicit ZeroedBuffer(std::size_t n);
  ~ZeroedBuffer();
  ZeroedBuffer(const ZeroedBuffer& other);
  ZeroedBuffer& operator=(const ZeroedBuffer& other);
  ZeroedBuffer(ZeroedBuffer&& other) noexcept;
  ZeroedBuffer& operator=(ZeroedBuffer&& other) noexcept;

  std::size_t size() const
  {
    return size_;
  }
  bool empty() const
  {
    return size_ == 0;
  }
  double* data()
  {
    return data_;
  }
  const double* data() const
  {
    return data_;
  }
  double& operator[](std::size_t i)
  {
    return data_[i];
  }
  const double& operator[](std::size_t i) const
  {
    return data_[i];
  }

private:
  void release() noexcept;
  void swap(ZeroedBuffer& other) noexcept;

  double* data_ = nullptr;
  std::size_t size_ = 0;
  bool mapped_ = false;  ///< from mmap (else from new[])
};

}  // namespace periodic_bias_compensation
