#pragma once
/// @file calibration.hpp  Fit the cup constants c1, c2 of the spring seal model to measured
/// outcomes.
///
/// An experiment is one measured suction attempt: a cup pose on a surface (typically the printed
/// calibration board) and whether it sealed. calibrate_cup() searches (c1, c2) so that the
/// nominal (unperturbed, one deterministic trial) prediction of the force-based spring model
/// (docs/models.md §1, SealModelKind::Spring) agrees with the measurements on a training split as
/// often as possible, and reports classification metrics on both splits (docs/models.md §4).
///
/// Search: the objective is piecewise constant in (c1, c2), so a derivative-free global search
/// (NLopt GN_DIRECT_L) runs over (log c1, log c2) inside the box first, then a local polish
/// (NLopt LN_BOBYQA) starts from the best point found. On a plateau the local step usually
/// cannot improve the accuracy; it then only moves along the plateau towards the tie-break
/// target below, which is intended.
///
/// Objective and ties (explicit and deterministic): minimise
///     f(x) = (1 - training accuracy) + w * |x - x0|^2,   x = (ln c1, ln c2),
/// with x0 = (ln c1, ln c2) of the initial cup and w = 1 / (2 n_train D^2), D^2 the largest
/// squared distance from x0 to a corner of the box. The penalty is below half an accuracy step
/// (1 / n_train), so accuracy always comes first; among points of equal accuracy the one closest
/// to the initial constants in log space wins; exact ties keep the earliest evaluation. The
/// initial constants (clamped into the box) are always the first evaluation, so a fit never
/// reports a worse training accuracy than the starting cup (when it lies in the box).

#include <mgn/core/types.hpp>
#include <mgn/geometry/mesh.hpp>
#include <mgn/grasp/cup.hpp>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace mgn {

/// One measured attempt.
struct CalibrationExperiment {
  std::size_t surface = 0;        ///< index into the surfaces given to calibrate_cup()
  Vec3d point = Vec3d::Zero();    ///< contact point on that surface mesh, m (surface frame)
  Vec3d normal = Vec3d::UnitZ();  ///< outward normal there (the cup approaches along -normal);
                                  ///< normalised on use
  bool sealed = false;            ///< measured outcome
};

/// Options of calibrate_cup().
struct CalibrationOptions {
  double c1_min = 1e-3, c1_max = 1.0;  ///< search box of c1 (0 < min < max)
  double c2_min = 1e-3, c2_max = 1.0;  ///< search box of c2 (0 < min < max)
  int global_evaluations = 200;        ///< GN_DIRECT_L budget (>= 1)
  int local_evaluations = 100;         ///< LN_BOBYQA budget (>= 0; 0 skips the local polish)
  double xtol_rel = 1e-4;              ///< relative step tolerance of both searches (> 0)
  double ftol_abs = 1e-9;              ///< absolute objective tolerance of both searches (> 0)
  /// Fraction of the experiments held out for the reported test metrics, in [0, 0.9]. The split
  /// is stratified: round(fraction * count) of the sealed and of the failed experiments each.
  double holdout_fraction = 0.3;
  std::uint64_t seed = 0;  ///< shuffling of the split (random stream (seed, 0) and (seed, 1))
  int num_threads = 0;     ///< seal evaluation threads, 0 = all hardware threads
};

/// Confusion counts and rates of a binary prediction ("positive" = sealed). A rate whose
/// denominator is zero (e.g. PPV with no predicted seal, or anything on an empty split) is NaN.
struct ClassificationMetrics {
  int tp = 0, fp = 0, tn = 0, fn = 0;
  double ppv = 0.0;          ///< tp / (tp + fp)  precision
  double npv = 0.0;          ///< tn / (tn + fn)
  double sensitivity = 0.0;  ///< tp / (tp + fn)  recall, true positive rate
  double specificity = 0.0;  ///< tn / (tn + fp)  true negative rate
  double accuracy = 0.0;     ///< (tp + tn) / count
};

/// Outcome of calibrate_cup().
struct CalibrationResult {
  Cup cup;                 ///< the initial cup with the fitted c1, c2
  double objective = 0.0;  ///< training accuracy of the fitted cup (the maximised quantity)
  int evaluations = 0;     ///< objective evaluations (initial point + global + local)
  ClassificationMetrics train, test;
  /// Experiment indices of the training and the held-out split, ascending.
  std::vector<std::size_t> train_indices, test_indices;
  /// The fitted cup's nominal prediction of every experiment (1 = seal).
  std::vector<std::uint8_t> predicted;
};

/// Fits c1 and c2 of `initial` (every other cup field is kept) to the experiments; see the file
/// comment for the objective. Throws InvalidArgument (naming the field or experiment) for no
/// experiments, a null or empty surface, a surface index out of range, a non-finite point or
/// normal, a zero normal, a point that is not on its surface, a bad search box (min <= 0 or
/// min >= max), bad budgets or tolerances, holdout_fraction outside [0, 0.9] or an invalid cup;
/// BackendError if NLopt fails (a roundoff-limited stop is not a failure: the best point found
/// so far is kept).
CalibrationResult calibrate_cup(const std::vector<const Mesh*>& surfaces,
                                const std::vector<CalibrationExperiment>& experiments,
                                const Cup& initial, const CalibrationOptions& options = {});

/// Nominal spring-model prediction (one deterministic trial, no perturbation) of every
/// experiment for `cup` (1 = seal); the `sealed` fields are ignored. Same validation as
/// calibrate_cup().
std::vector<std::uint8_t> predict_experiments(const std::vector<const Mesh*>& surfaces,
                                              const std::vector<CalibrationExperiment>& experiments,
                                              const Cup& cup, int num_threads = 0);

/// Metrics of `predicted` against `measured` (non-zero = sealed). Throws InvalidArgument if the
/// lengths differ. Empty inputs give zero counts and NaN rates.
ClassificationMetrics classification_metrics(const std::vector<std::uint8_t>& predicted,
                                             const std::vector<std::uint8_t>& measured);

}  // namespace mgn
