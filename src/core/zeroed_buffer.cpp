#include "periodic_bias_compensation/core/zeroed_buffer.h"

#include <sys/mman.h>

#include <algorithm>
#include <new>
#include <utility>

namespace periodic_bias_compensation
{
ZeroedBuffer::ZeroedBuffer(std::size_t n) : size_(n)
{
  if (n == 0)
    return;
  if (n > static_cast<std::size_t>(-1) / sizeof(double))
    throw std::bad_alloc();
  const std::size_t bytes = n * sizeof(double);
  if (bytes < kMappedBytes)
  {
    data_ = new double[n]();
    return;
  }
  // Anonymous pages read as zero and are cleared by the kernel on their first write.
  void* memory = mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (memory == MAP_FAILED)
    throw std::bad_alloc();
  data_ = static_cast<double*>(memory);
  mapped_ = true;
}

ZeroedBuffer::~ZeroedBuffer()
{
  release();
}

ZeroedBuffer::ZeroedBuffer(const ZeroedBuffer& other) : ZeroedBuffer(other.size_)
{
  std::copy(other.data_, other.data_ + other.size_, data_);
}

ZeroedBuffer& ZeroedBuffer::operator=(const ZeroedBuffer& other)
{
  if (this != &other)
  {
    ZeroedBuffer copy(other);
    swap(copy);
  }
  return *this;
}

ZeroedBuffer::ZeroedBuffer(ZeroedBuffer&& other) noexcept
{
  swap(other);
}

ZeroedBuffer& ZeroedBuffer::operator=(ZeroedBuffer&& other) noexcept
{
  ZeroedBuffer moved(std::move(other));
  swap(moved);
  return *this;
}

void ZeroedBuffer::release() noexcept
{
  if (mapped_)
    munmap(data_, size_ * sizeof(double));
  else
    delete[] data_;
  data_ = nullptr;
  size_ = 0;
  mapped_ = false;
}

void ZeroedBuffer::swap(ZeroedBuffer& other) noexcept
{
  std::swap(data_, other.data_);
  std::swap(size_, other.size_);
  std::swap(mapped_, other.mapped_);
}

}  // namespace periodic_bias_compensation
