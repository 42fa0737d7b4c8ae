/// @file pixel_loop.cpp
/// See pixel_loop.h.

#include "integrators/pixel_loop.h"

#include <tbb/blocked_range2d.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <mutex>

namespace qsil {

void for_each_pixel(int width, int height, int threads, const std::string& label,
                    const std::function<void(int, int)>& body) {
  using clock = std::chrono::steady_clock;
  const auto start = clock::now();
  std::atomic<long long> done{0};
  std::mutex print_mutex;
  std::atomic<bool> printed{false};
  auto last_print = start;
  const long long total = (long long)width * height;
  auto run = [&] {
    tbb::parallel_for(tbb::blocked_range2d<int>(0, height, 16, 0, width, 16), [&](const tbb::blocked_range2d<int>& r) {
      for (int y = r.rows().begin(); y < r.rows().end(); ++y)
        for (int x = r.cols().begin(); x < r.cols().end(); ++x) body(x, y);
      const long long d =
          done.fetch_add((long long)r.rows().size() * r.cols().size()) + (long long)r.rows().size() * r.cols().size();
      if (label.empty()) return;
      const auto now = clock::now();
      if (now - start < std::chrono::seconds(1)) return;
      std::unique_lock lock(print_mutex, std::try_to_lock);
      if (!lock.owns_lock() || now - last_print < std::chrono::milliseconds(250)) return;
      last_print = now;
      const int width_bar = 30;
      const double frac = double(d) / double(total);
      const int filled = int(frac * width_bar);
      std::fprintf(stderr, "\r%s [%.*s%*s] %5.1f%%", label.c_str(), filled, "##############################",
                   width_bar - filled, "", 100.0 * frac);
      std::fflush(stderr);
      printed = true;
    });
  };
  if (threads > 0) {
    tbb::task_arena arena(threads);
    arena.execute(run);
  } else {
    run();
  }
  if (printed) std::fprintf(stderr, "\r%s [##############################] 100.0%%\n", label.c_str());
}

}  // namespace qsil
