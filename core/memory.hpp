#pragma once
// The memory a job may use: what the machine has available, sizes as users write them.

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <type_traits>
#include <utility>

namespace lambert {

/// MemAvailable from /proc/meminfo in bytes, or nullopt where it cannot be read.
std::optional<double> available_memory_bytes();

/// Parses a size: a decimal number (digits and one optional '.') followed by nothing (bytes)
/// or K, M, G, T (powers of 1024), optionally with B or iB after it, case-insensitive
/// ("512M", "8G", "1.5GiB"); nullopt for anything else or beyond 2^63 bytes.
std::optional<double> parse_size(const std::string& text);

/// Formats bytes with a binary suffix, e.g. "11.2 GiB".
std::string format_bytes(double bytes);

/// An allocator whose resize() leaves new elements as the memory was (no zeroing pass):
/// for arrays of plain data that parallel loops fill, so that nothing touches a page of a
/// large array before the thread that writes it (serial zeroing faults every page in on
/// one thread). Elements constructed with arguments are constructed as usual.
template <class T>
struct UninitializedAllocator : std::allocator<T> {
  using value_type = T;
  template <class U>
  struct rebind {
    using other = UninitializedAllocator<U>;
  };
  UninitializedAllocator() = default;
  template <class U>
  UninitializedAllocator(const UninitializedAllocator<U>&) noexcept {}
  template <class U>
  void construct(U*) noexcept {
    static_assert(std::is_trivially_copyable<U>::value, "plain data only");
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};

}  // namespace lambert
