#pragma once
/// @file pixel_loop.h
/// Parallel loop over the pixels of an image with oneTBB, with a progress bar on stderr for runs
/// longer than a second. Each pixel is processed by exactly one task, and its samples are drawn
/// from streams seeded by (seed, pixel, sample), so results do not depend on the thread count.

#include <functional>
#include <string>

namespace qsil {

/// Calls body(x, y) for every pixel of a width x height image, in parallel over 16x16 tiles on
/// `threads` threads (0 = all cores). `label` prefixes the progress bar ("" = no bar).
void for_each_pixel(int width, int height, int threads, const std::string& label,
                    const std::function<void(int x, int y)>& body);

}  // namespace qsil
