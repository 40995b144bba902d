#pragma once
// Private: how shake_test shares the staircase searches of many grasps between threads (see
// staircase_grid() in mgn/grasp/shake_trial.hpp for the search itself).
#include <mgn/grasp/shake_trial.hpp>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

namespace mgn::detail {

/// staircase_grid() without its fallback: when a check contradicts its inference, `fallback` is
/// set and the cells not simulated yet keep their inferred values (the caller simulates them).
StaircaseGrid staircase_walk(int S, const std::function<bool(int, int)>& trial, int checks,
                             int verified_rows = -1);

/// A worker's trial function: runs trial t = g·S² + i·S + j (grasp g, cell (i, j)) and returns
/// its success. Each worker gets its own (made on its thread), so it may hold per-thread state.
using TrialRunner = std::function<bool(std::size_t)>;

/// The staircase search of `grasps` grasps on up to num_threads threads (0 = all), exactly the
/// results of staircase_grid() per grasp whatever the thread count: success (G·S²) gets every
/// cell (simulated or inferred), fallback (G) the grasps that fell back. Threads take grasps one
/// at a time; the remaining cells of a grasp that falls back go to a shared list that every
/// thread takes from first, and threads without a grasp left wait for them while walks still
/// run, so one slow grasp at the end is not simulated by one thread alone. `make_runner` is
/// called once per worker thread. The first exception of a trial is re-thrown.
void staircase_schedule(std::size_t grasps, int S, int checks, int verified_rows, int num_threads,
                        const std::function<TrialRunner()>& make_runner,
                        std::vector<std::uint8_t>& success, std::vector<std::uint8_t>& fallback);

}  // namespace mgn::detail
