/// @file pixel_loop.cpp
/// See pixel_loop.h.

#include "pixel_loop.h"

#include <tbb/blocked_range.h>
#include <tbb/blocked_range2d.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <mutex>

namespace qsil {

void for_each_pixel(int width, int height, int threads, const std::string& label,
                    const std::function<void(int, int)>& body, int part, int parts) {
  using clock = std::chrono::steady_clock;
  const auto start = clock::now();
  std::atomic<long long> done{0};
  std::mutex print_mutex;
  std::atomic<bool> printed{false};
  auto last_print = start;
  const long long pixels = (long long)width * height;
  // The part's pixels are part, part + parts, ... (Film::part_of).
  const long long total = parts > 1 ? (pixels - part + parts - 1) / parts : pixels;
  // After `n` more pixels are done: the progress bar.
  auto progress = [&](long long n) {
    const long long d = done.fetch_add(n) + n;
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
  };
  auto run = [&] {
    if (parts > 1) {
      tbb::parallel_for(tbb::blocked_range<long long>(0, total, 64), [&](const tbb::blocked_range<long long>& r) {
        for (long long i = r.begin(); i < r.end(); ++i) {
          const long long p = part + i * parts;
          body(int(p % width), int(p / width));
        }
        progress((long long)r.size());
      });
      return;
    }
    tbb::parallel_for(tbb::blocked_range2d<int>(0, height, 16, 0, width, 16), [&](const tbb::blocked_range2d<int>& r) {
      for (int y = r.rows().begin(); y < r.rows().end(); ++y)
        for (int x = r.cols().begin(); x < r.cols().end(); ++x) body(x, y);
      progress((long long)r.rows().size() * r.cols().size());
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
