#pragma once
// FFTW's planner is not thread-safe (fftw_execute is): every translation unit
// of fast/ makes and destroys its plans under this one lock, so that Monte
// Carlo runs may identify in threads.
#include <mutex>

namespace fdsid::detail {
std::mutex& fftw_planner_mutex();
}  // namespace fdsid::detail
