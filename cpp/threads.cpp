#include "threads.hpp"

#include <pthread.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <exception>
#include <limits>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <unordered_map>

namespace thinburn {
namespace {

std::atomic<int> g_default_threads{1};
thread_local int t_threads = 0;  // 0: no ScopedThreads in force on this thread

void cpu_relax() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();
#endif
}

// One parallel loop in flight. Shared with the helpers through a shared_ptr, so a helper
// that wakes after the loop has ended still holds a valid (finished) job.
struct Job {
  void (*task)(void*, long);
  void* ctx;
  long chunks;
  std::atomic<long> next{0};      // the next chunk to claim
  std::atomic<long> done{0};      // chunks ended (run, or skipped after a failure)
  std::atomic<int> seats{0};      // helpers that may still join
  std::atomic<bool> failed{false};
  std::mutex error_mutex;
  std::exception_ptr error;
};

// Claims chunks until none is left. A chunk is claimed only while the caller is still
// waiting for it, so task and ctx are valid whenever they are used.
long work_on(Job& job) {
  long ran = 0;
  for (long c; (c = job.next.fetch_add(1, std::memory_order_relaxed)) < job.chunks; ++ran) {
    if (!job.failed.load(std::memory_order_relaxed)) {
      try {
        job.task(job.ctx, c);
      } catch (...) {
        std::lock_guard<std::mutex> lock(job.error_mutex);
        if (!job.error) job.error = std::current_exception();
        job.failed.store(true, std::memory_order_relaxed);
      }
    }
    job.done.fetch_add(1, std::memory_order_release);
  }
  return ran;
}

// Helpers sleep on a condition variable between loops (a passive wait: an idle helper takes
// no core from anyone). After a loop a helper watches for the next one for a few
// microseconds first, since the loops of a step come in quick succession.
class Pool {
 public:
  // Returns false, running nothing, when another loop holds the pool (another thread's
  // Simulation, or a loop nested in a chunk): the caller then runs its loop alone.
  bool try_run(long chunks, int helpers, void (*task)(void*, long), void* ctx) {
    bool expected = false;
    if (!busy_.compare_exchange_strong(expected, true, std::memory_order_acquire)) return false;
    Site& site = sites_[task];  // one entry per parallel_for call site (its task function)
    if (site.skip > 0) {  // helpers were of no use at this loop lately: run it alone for a while
      --site.skip;
      busy_.store(false, std::memory_order_release);
      return false;
    }
    using Clock = std::chrono::steady_clock;
    const auto start = Clock::now();
    auto job = std::make_shared<Job>();
    job->task = task;
    job->ctx = ctx;
    job->chunks = chunks;
    job->seats.store(helpers, std::memory_order_relaxed);
    {
      std::lock_guard<std::mutex> lock(mutex_);
      grow(helpers);
      job_ = job;
      generation_.fetch_add(1, std::memory_order_release);
      if (sleeping_ > 0) {
        if (helpers >= workers_)
          wake_.notify_all();
        else
          for (int h = 0; h < helpers; ++h) wake_.notify_one();
      }
    }
    const long mine = work_on(*job);
    const auto own_end = Clock::now();
    // Only chunks already claimed by a running helper are waited for.
    for (int spin = 0; job->done.load(std::memory_order_acquire) < chunks; ++spin) {
      if (spin < 256)
        cpu_relax();
      else
        std::this_thread::yield();
    }
    {
      std::lock_guard<std::mutex> lock(mutex_);
      job_.reset();
    }
    learn(site, mine < chunks, Clock::now() - own_end, own_end - start);
    busy_.store(false, std::memory_order_release);
    if (job->error) std::rethrow_exception(job->error);
    return true;
  }

  // After fork() only the forking thread exists in the child: start from an empty pool (the
  // old one, whose mutex a helper may have held, is abandoned).
  static void reset_after_fork() { instance_ = new Pool(); }

  static Pool& instance() { return *instance_; }

 private:
  // Helpers are of use at a loop when they took chunks and the caller did not wait long for
  // them. When they are not (a loop too short for a sleeping helper to wake in time, or every
  // core busy: a woken helper gets no core in time, or loses it mid-chunk), the next 2^k - 1
  // runs of that loop (its call site) run on the caller alone, k growing with each useless run
  // in a row, so a busy machine pays for a probe now and then instead of a wake-up every time,
  // and a short loop's verdict does not keep helpers from a long one.
  struct Site {
    int backoff = 0, skip = 0;
  };
  static void learn(Site& site, bool helped, std::chrono::steady_clock::duration waited,
                    std::chrono::steady_clock::duration worked) {
    constexpr int kMaxBackoff = 10;  // at most 1023 runs alone between probes
    if (helped && waited * 4 <= worked) {
      site.backoff = 0;
      return;
    }
    site.backoff = std::min(site.backoff + 1, kMaxBackoff);
    site.skip = (1 << site.backoff) - 1;
  }

  void grow(int helpers) {
    while (workers_ < helpers) {
      // Helpers beyond the cores never watch: they would spin on the cores the caller needs.
      const bool may_watch = workers_ + 1 < hardware_threads();
      std::thread t([this, may_watch] { helper_main(may_watch); });
      t.detach();  // helpers live as long as the process; nothing joins them at exit
      ++workers_;
    }
  }

  // Watches for the next loop for kWatch before the helper goes to sleep.
  void watch(std::uint64_t seen) const {
    constexpr auto kWatch = std::chrono::microseconds(20);
    const auto until = std::chrono::steady_clock::now() + kWatch;
    for (int i = 0; generation_.load(std::memory_order_acquire) == seen; ++i) {
      cpu_relax();
      if ((i & 63) == 63 && std::chrono::steady_clock::now() >= until) return;
    }
  }

  void helper_main(bool may_watch) {
    std::uint64_t seen = generation_.load(std::memory_order_acquire);
    bool did_work = false;
    for (;;) {
      if (may_watch && did_work) watch(seen);
      std::shared_ptr<Job> job;
      {
        std::unique_lock<std::mutex> lock(mutex_);
        ++sleeping_;
        wake_.wait(lock, [&] { return generation_.load(std::memory_order_acquire) != seen; });
        --sleeping_;
        seen = generation_.load(std::memory_order_acquire);
        job = job_;
      }
      // A helper that found the loop already done goes back to sleep at once: it came late
      // (a busy machine, or a short loop), and watching would only take a core from the caller.
      did_work = job && job->seats.fetch_sub(1, std::memory_order_relaxed) > 0 && work_on(*job) > 0;
    }
  }

  static Pool* instance_;
  std::atomic<bool> busy_{false};
  std::atomic<std::uint64_t> generation_{0};
  std::mutex mutex_;
  std::condition_variable wake_;
  std::shared_ptr<Job> job_;
  int workers_ = 0;  // helpers started (they never end)
  int sleeping_ = 0;
  std::unordered_map<void (*)(void*, long), Site> sites_;  // touched only by busy_'s holder
};

Pool* Pool::instance_ = [] {
  pthread_atfork(nullptr, nullptr, &Pool::reset_after_fork);
  return new Pool();
}();

}  // namespace

int hardware_threads() { return std::max(1u, std::thread::hardware_concurrency()); }

int max_threads() { return std::max(8, 4 * hardware_threads()); }

namespace {
void check_count(int n) {
  if (n < 1 || n > max_threads())
    throw std::invalid_argument("threads must be in [1, " + std::to_string(max_threads()) +
                                "] (4 x the " + std::to_string(hardware_threads()) +
                                " logical cores, at least 8), got " + std::to_string(n));
}
}  // namespace

void set_num_threads(int n) {
  check_count(n);
  g_default_threads = n;
}

int num_threads() { return t_threads > 0 ? t_threads : g_default_threads.load(); }

ScopedThreads::ScopedThreads(int n) : previous_(t_threads) {
  check_count(n);
  t_threads = n;
}

ScopedThreads::~ScopedThreads() { t_threads = previous_; }

namespace detail {
void run_chunks(long chunks, int helpers, void (*task)(void*, long), void* ctx) {
  if (helpers > 0 && Pool::instance().try_run(chunks, helpers, task, ctx)) return;
  for (long c = 0; c < chunks; ++c) task(ctx, c);
}
}  // namespace detail

namespace {

double triad_seconds(double* a, const double* b, const double* c, long n, double s) {
  const auto t0 = std::chrono::steady_clock::now();
  parallel_for(0, n, 1, [&](long i) { a[i] = b[i] + s * c[i]; });
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

double measure_memory_bandwidth(std::size_t bytes, int repeat) {
  constexpr std::size_t kMinBytes = 3 * sizeof(double) * 1024;
  if (bytes < kMinBytes)
    throw std::invalid_argument("bytes must be >= " + std::to_string(kMinBytes) + ", got " +
                                std::to_string(bytes));
  if (repeat < 1) throw std::invalid_argument("repeat must be >= 1, got " + std::to_string(repeat));
  const auto n = static_cast<long>(bytes / (3 * sizeof(double)));
  std::unique_ptr<double[]> a(new double[n]), b(new double[n]), c(new double[n]);
  parallel_for(0, n, 1, [&](long i) {
    a[i] = 0.0;
    b[i] = 1.0;
    c[i] = 2.0;
  });
  double best = std::numeric_limits<double>::infinity();
  for (int k = 0; k < repeat; ++k) best = std::min(best, triad_seconds(a.get(), b.get(), c.get(), n, 0.5 + k));
  // The result is read so the passes cannot be dropped as dead stores.
  if (!(a[n / 2] > 0.0) || !(best > 0.0)) throw std::runtime_error("memory bandwidth probe failed");
  return 3.0 * sizeof(double) * static_cast<double>(n) / best;
}

}  // namespace thinburn
