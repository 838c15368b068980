#pragma once
/// @brief The core's threads: one explicit count, one parallel loop, one threshold.
///
/// Every parallel loop of the core is a `parallel_for`. The work is cut into chunks that the
/// calling thread and the pool's helpers claim one at a time; the caller never waits for a
/// helper that has not claimed a chunk. On a busy machine, where a helper may not get a core
/// for milliseconds, the caller simply does all the chunks itself, so a second thread never
/// costs more than a few microseconds per loop (OpenMP's fork-join waits at every region for
/// every member of its team, which made a busy machine 7-23x slower; docs/threads.md).
///
/// Results never depend on the thread count: each item writes only its own outputs, and
/// reductions sum fixed chunks in a fixed order.
#include <cstddef>

namespace thinburn {

/// @brief Loops with less work than this (in units of a few flops: items times the cost of
/// one) run on the calling thread alone. Waking a helper costs a few microseconds; a loop
/// shorter than some tens of microseconds gains nothing from it.
constexpr long kParallelWork = 1L << 15;

/// @brief Logical cores of this machine (>= 1).
int hardware_threads();

/// @brief The largest thread count accepted: 4 x hardware_threads(), at least 8. More
/// threads than cores never help; a typo such as 10**9 must not start a billion threads.
int max_threads();

/// @brief Set the default thread count (1..max_threads()), used on any thread that has no
/// ScopedThreads in force.
void set_num_threads(int n);

/// @brief The thread count in force on the calling thread.
int num_threads();

/// @brief Sets the calling thread's count for its lifetime, so that several Simulations,
/// each with its own count, can run from several threads at once.
class ScopedThreads {
 public:
  explicit ScopedThreads(int n);
  ~ScopedThreads();
  ScopedThreads(const ScopedThreads&) = delete;
  ScopedThreads& operator=(const ScopedThreads&) = delete;

 private:
  int previous_;
};

namespace detail {
/// @brief Calls task(ctx, c) for every chunk c in [0, chunks), on the caller and up to
/// helpers pool threads; rethrows the first exception a chunk threw, after all have ended.
void run_chunks(long chunks, int helpers, void (*task)(void*, long), void* ctx);
}  // namespace detail

/// @brief body(i) for i in [begin, end), in parallel when (end - begin) * cost >= kParallelWork
/// and num_threads() > 1. `cost` is one item's work in the units of kParallelWork.
template <class Body>
void parallel_for(long begin, long end, long cost, Body&& body) {
  const long n = end - begin;
  if (n <= 0) return;
  const int threads = num_threads();
  const long work = n * (cost > 0 ? cost : 1);
  if (threads <= 1 || n < 2 || work < kParallelWork) {
    for (long i = begin; i < end; ++i) body(i);
    return;
  }
  // Chunks of at least an eighth of the threshold's work, about eight per thread: small
  // enough that the caller can take over a late helper's share, large enough that claiming
  // one (an atomic add) costs nothing next to its work.
  const long by_work = work / (kParallelWork / 8);
  long chunks = 8L * threads;
  if (chunks > by_work) chunks = by_work;
  if (chunks > n) chunks = n;
  if (chunks < 2) chunks = 2;
  struct Ctx {
    Body* body;
    long begin, n, chunks;
  } ctx{&body, begin, n, chunks};
  detail::run_chunks(chunks, threads - 1, [](void* p, long c) {
    const Ctx& x = *static_cast<Ctx*>(p);
    const long lo = x.begin + x.n * c / x.chunks, hi = x.begin + x.n * (c + 1) / x.chunks;
    for (long i = lo; i < hi; ++i) (*x.body)(i);
  }, &ctx);
}

/// @brief Machine probe: sustained memory bandwidth of a STREAM-style triad a = b + s c on
/// num_threads() threads.
/// @param bytes total size of the three double arrays (>= 3 * 8 * 1024); to measure main
/// memory, make it several times the last-level cache.
/// @param repeat timed passes (>= 1); the fastest is kept.
/// @return bytes moved per second, counted as STREAM does: 24 bytes per element (two reads,
/// one write; the write-allocate read of a is not counted).
double measure_memory_bandwidth(std::size_t bytes, int repeat);

}  // namespace thinburn
