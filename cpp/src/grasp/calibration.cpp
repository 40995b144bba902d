// Cup calibration (docs/models.md §4): fit c1, c2 of the spring seal model to measured outcomes
// with NLopt (GN_DIRECT_L, then LN_BOBYQA) over (ln c1, ln c2). See calibration.hpp for the
// objective and the tie rule.
#include <mgn/core/error.hpp>
#include <mgn/core/rng.hpp>
#include <mgn/grasp/calibration.hpp>
#include <mgn/grasp/seal_model.hpp>

#include <nlopt.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <exception>
#include <limits>
#include <memory>
#include <numeric>
#include <string>

namespace mgn {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

void check_box(const char* fn, const char* name, double lo, double hi) {
  if (!(lo > 0.0) || !std::isfinite(lo) || !std::isfinite(hi) || !(lo < hi)) {
    throw_error<InvalidArgument>(
        fn, ": options.", name, "_min and options.", name, "_max must satisfy 0 < ", name,
        "_min < ", name, "_max (finite), got ", name, "_min = ", lo, ", ", name, "_max = ", hi);
  }
}

void check_options(const char* fn, const CalibrationOptions& o) {
  check_box(fn, "c1", o.c1_min, o.c1_max);
  check_box(fn, "c2", o.c2_min, o.c2_max);
  if (o.global_evaluations < 1) {
    throw_error<InvalidArgument>(fn, ": options.global_evaluations must be >= 1, got ",
                                 o.global_evaluations);
  }
  if (o.local_evaluations < 0) {
    throw_error<InvalidArgument>(fn, ": options.local_evaluations must be >= 0, got ",
                                 o.local_evaluations);
  }
  if (!(o.xtol_rel > 0.0) || !std::isfinite(o.xtol_rel)) {
    throw_error<InvalidArgument>(fn, ": options.xtol_rel must be finite and > 0, got ", o.xtol_rel);
  }
  if (!(o.ftol_abs > 0.0) || !std::isfinite(o.ftol_abs)) {
    throw_error<InvalidArgument>(fn, ": options.ftol_abs must be finite and > 0, got ", o.ftol_abs);
  }
  if (!(o.holdout_fraction >= 0.0 && o.holdout_fraction <= 0.9)) {
    throw_error<InvalidArgument>(fn, ": options.holdout_fraction must be in [0, 0.9], got ",
                                 o.holdout_fraction);
  }
  if (o.num_threads < 0) {
    throw_error<InvalidArgument>(fn, ": options.num_threads must be >= 0 (0 = all), got ",
                                 o.num_threads);
  }
}

void check_experiments(const char* fn, const std::vector<const Mesh*>& surfaces,
                       const std::vector<CalibrationExperiment>& experiments) {
  if (experiments.empty())
    throw_error<InvalidArgument>(fn, ": experiments: expected at least one, got none");
  for (std::size_t j = 0; j < experiments.size(); ++j) {
    const CalibrationExperiment& e = experiments[j];
    if (e.surface >= surfaces.size()) {
      throw_error<InvalidArgument>(fn, ": experiments[", j, "].surface = ", e.surface,
                                   " is out of range (expected < ", surfaces.size(),
                                   ", the number of surfaces)");
    }
    if (surfaces[e.surface] == nullptr) {
      throw_error<InvalidArgument>(fn, ": surfaces[", e.surface, "] (used by experiments[", j,
                                   "]) is null");
    }
    if (!e.point.allFinite()) {
      throw_error<InvalidArgument>(fn, ": experiments[", j,
                                   "].point: expected finite coordinates, got (", e.point.x(), ", ",
                                   e.point.y(), ", ", e.point.z(), ")");
    }
    if (!e.normal.allFinite() || !(e.normal.norm() > 0.0)) {
      throw_error<InvalidArgument>(fn, ": experiments[", j,
                                   "].normal: expected a finite non-zero vector, got (",
                                   e.normal.x(), ", ", e.normal.y(), ", ", e.normal.z(), ")");
    }
  }
}

/// Nominal spring-model predictions of (subsets of) the experiments: one SealModel per used
/// surface, built once; other cups share its ray scene through SealModel::with_cup().
class Predictor {
 public:
  Predictor(const char* fn, const std::vector<const Mesh*>& surfaces,
            const std::vector<CalibrationExperiment>& experiments, const Cup& cup, int num_threads)
      : fn_(fn), experiments_(experiments), num_threads_(num_threads) {
    models_.resize(surfaces.size());
    for (const CalibrationExperiment& e : experiments) {
      if (models_[e.surface]) continue;
      try {
        models_[e.surface] =
            std::make_unique<SealModel>(*surfaces[e.surface], cup, SealModelKind::Spring);
      } catch (const InvalidArgument& err) {
        throw_error<InvalidArgument>(fn, ": surfaces[", e.surface, "]: ", err.what());
      }
    }
  }

  /// Writes pred[j] (1 = seal) and, if given, reason[j] (SealFailure) for every j in `subset`.
  void predict(const Cup& cup, const std::vector<std::size_t>& subset,
               std::vector<std::uint8_t>& pred, std::vector<std::uint8_t>* reason) const {
    SealOptions opt;
    opt.perturb = false;
    opt.num_trials = 1;
    opt.num_threads = num_threads_;
    std::vector<std::size_t> rows;
    for (std::size_t s = 0; s < models_.size(); ++s) {
      if (!models_[s]) continue;
      rows.clear();
      for (std::size_t j : subset) {
        if (experiments_[j].surface == s) rows.push_back(j);
      }
      if (rows.empty()) continue;
      const auto n = static_cast<Eigen::Index>(rows.size());
      Points3f points(n, 3), normals(n, 3);
      for (Eigen::Index i = 0; i < n; ++i) {
        const CalibrationExperiment& e = experiments_[rows[static_cast<std::size_t>(i)]];
        points.row(i) = e.point.cast<float>().transpose();
        normals.row(i) = e.normal.normalized().cast<float>().transpose();
      }
      const std::shared_ptr<const SealModel> model = models_[s]->with_cup(cup);
      SealResult r;
      try {
        r = model->evaluate(points, normals, opt);
      } catch (const InvalidArgument&) {
        name_bad_experiment(*model, rows, points, normals, opt);
        throw;
      }
      for (std::size_t i = 0; i < rows.size(); ++i) {
        pred[rows[i]] = r.trial_sealed[i];
        if (reason) (*reason)[rows[i]] = r.trial_reason[i];
      }
    }
  }

 private:
  /// After a batch was rejected: evaluates the candidates one by one and rethrows the first
  /// error with the experiment it belongs to.
  void name_bad_experiment(const SealModel& model, const std::vector<std::size_t>& rows,
                           const Points3f& points, const Points3f& normals,
                           const SealOptions& opt) const {
    for (std::size_t i = 0; i < rows.size(); ++i) {
      const auto k = static_cast<Eigen::Index>(i);
      try {
        model.evaluate(points.row(k), normals.row(k), opt);
      } catch (const InvalidArgument& err) {
        throw_error<InvalidArgument>(fn_, ": experiments[", rows[i], "] (surface ",
                                     experiments_[rows[i]].surface, "): ", err.what());
      }
    }
  }

  const char* fn_;
  const std::vector<CalibrationExperiment>& experiments_;
  int num_threads_;
  std::vector<std::unique_ptr<SealModel>> models_;
};

/// Stratified shuffled split: round(fraction * count) of each measured class go to the test set.
void split(const std::vector<CalibrationExperiment>& experiments, double fraction,
           std::uint64_t seed, std::vector<std::size_t>& train, std::vector<std::size_t>& test) {
  train.clear();
  test.clear();
  for (int cls = 0; cls < 2; ++cls) {
    std::vector<std::size_t> idx;
    for (std::size_t j = 0; j < experiments.size(); ++j) {
      if (static_cast<int>(experiments[j].sealed) == cls) idx.push_back(j);
    }
    Rng rng(seed, static_cast<std::uint64_t>(cls));
    for (std::size_t i = idx.size(); i > 1; --i)
      std::swap(idx[i - 1], idx[rng.below(i)]);  // Fisher-Yates
    const auto n_test =
        static_cast<std::size_t>(std::floor(fraction * static_cast<double>(idx.size()) + 0.5));
    test.insert(test.end(), idx.begin(), idx.begin() + static_cast<std::ptrdiff_t>(n_test));
    train.insert(train.end(), idx.begin() + static_cast<std::ptrdiff_t>(n_test), idx.end());
  }
  if (train.empty()) {  // tiny inputs: keep at least one training experiment
    train.push_back(test.back());
    test.pop_back();
  }
  std::sort(train.begin(), train.end());
  std::sort(test.begin(), test.end());
}

/// The search state shared by the NLopt callbacks: tracks the best point under the tie rule.
struct Search {
  const Predictor* predictor = nullptr;
  const std::vector<CalibrationExperiment>* experiments = nullptr;
  Cup cup;                           // template; c1, c2 replaced per evaluation
  std::vector<std::size_t> varying;  // training experiments whose prediction depends on c1, c2
  int fixed_correct = 0;             // training experiments predicted "no seal" for any c1, c2
  int n_train = 0;
  std::array<double, 2> x0{};  // (ln c1, ln c2) of the initial cup
  double weight = 0.0;         // tie-break penalty weight
  int evaluations = 0;
  bool has_best = false;
  int best_correct = 0;
  double best_dist2 = 0.0;
  std::array<double, 2> best_x{};
  std::array<double, 2> best_c{};  // (c1, c2) of best_x, exactly as evaluated
  std::exception_ptr error;
  std::vector<std::uint8_t> pred;  // scratch, indexed by experiment

  double evaluate(const double* x) { return evaluate(x, std::exp(x[0]), std::exp(x[1])); }

  /// Evaluates the point x = (ln c1, ln c2); c1, c2 are passed too so that the initial
  /// constants are evaluated (and reported) exactly, without a log/exp round trip.
  double evaluate(const double* x, double c1, double c2) {
    ++evaluations;
    Cup c = cup;
    c.c1 = c1;
    c.c2 = c2;
    predictor->predict(c, varying, pred, nullptr);
    int correct = fixed_correct;
    for (std::size_t j : varying) correct += (pred[j] != 0) == (*experiments)[j].sealed;
    const double dx = x[0] - x0[0], dy = x[1] - x0[1];
    const double dist2 = dx * dx + dy * dy;
    // Lexicographic: more correct, then closer to the initial constants, then earlier.
    if (!has_best || correct > best_correct || (correct == best_correct && dist2 < best_dist2)) {
      has_best = true;
      best_correct = correct;
      best_dist2 = dist2;
      best_x = {x[0], x[1]};
      best_c = {c1, c2};
    }
    return static_cast<double>(n_train - correct) / n_train + weight * dist2;
  }
};

double objective(unsigned n, const double* x, double* grad, void* data) {
  auto* s = static_cast<Search*>(data);
  try {
    return s->evaluate(x);
  } catch (...) {
    // NLopt swallows exceptions thrown by the objective; keep ours and stop the search.
    s->error = std::current_exception();
    throw nlopt::forced_stop();
  }
}

/// Runs one NLopt search from x (in place). A roundoff-limited stop keeps the best point found.
void run_search(const char* fn, nlopt::algorithm algorithm, const char* name, int max_evaluations,
                const std::vector<double>& lb, const std::vector<double>& ub,
                const CalibrationOptions& options, Search& search, std::vector<double> x) {
  try {
    nlopt::opt opt(algorithm, 2);
    opt.set_lower_bounds(lb);
    opt.set_upper_bounds(ub);
    opt.set_min_objective(objective, &search);
    opt.set_xtol_rel(options.xtol_rel);
    opt.set_ftol_abs(options.ftol_abs);
    opt.set_maxeval(max_evaluations);
    if (algorithm == nlopt::LN_BOBYQA)
      opt.set_initial_step({0.1 * (ub[0] - lb[0]), 0.1 * (ub[1] - lb[1])});
    double f = 0.0;
    opt.optimize(x, f);
  } catch (const nlopt::roundoff_limited&) {
    // Progress limited by roundoff: the points evaluated so far are valid; keep the best.
  } catch (const std::exception& e) {
    if (search.error) std::rethrow_exception(search.error);
    throw_error<BackendError>(fn, ": NLopt ", name, " failed: ", e.what());
  }
  if (search.error) std::rethrow_exception(search.error);
}

}  // namespace

ClassificationMetrics classification_metrics(const std::vector<std::uint8_t>& predicted,
                                             const std::vector<std::uint8_t>& measured) {
  if (predicted.size() != measured.size()) {
    throw_error<InvalidArgument>("classification_metrics: predicted has ", predicted.size(),
                                 " entries but measured has ", measured.size(),
                                 "; expected equal lengths");
  }
  ClassificationMetrics m;
  for (std::size_t i = 0; i < predicted.size(); ++i) {
    const bool p = predicted[i] != 0, y = measured[i] != 0;
    m.tp += p && y;
    m.fp += p && !y;
    m.tn += !p && !y;
    m.fn += !p && y;
  }
  const auto rate = [](int num, int den) {
    return den > 0 ? static_cast<double>(num) / den : kNaN;
  };
  m.ppv = rate(m.tp, m.tp + m.fp);
  m.npv = rate(m.tn, m.tn + m.fn);
  m.sensitivity = rate(m.tp, m.tp + m.fn);
  m.specificity = rate(m.tn, m.tn + m.fp);
  m.accuracy = rate(m.tp + m.tn, m.tp + m.fp + m.tn + m.fn);
  return m;
}

std::vector<std::uint8_t> predict_experiments(const std::vector<const Mesh*>& surfaces,
                                              const std::vector<CalibrationExperiment>& experiments,
                                              const Cup& cup, int num_threads) {
  const char* fn = "predict_experiments";
  check_experiments(fn, surfaces, experiments);
  if (num_threads < 0)
    throw_error<InvalidArgument>(fn, ": num_threads must be >= 0 (0 = all), got ", num_threads);
  cup.validate();
  const Predictor predictor(fn, surfaces, experiments, cup, num_threads);
  std::vector<std::size_t> all(experiments.size());
  std::iota(all.begin(), all.end(), std::size_t{0});
  std::vector<std::uint8_t> pred(experiments.size(), 0);
  predictor.predict(cup, all, pred, nullptr);
  return pred;
}

CalibrationResult calibrate_cup(const std::vector<const Mesh*>& surfaces,
                                const std::vector<CalibrationExperiment>& experiments,
                                const Cup& initial, const CalibrationOptions& options) {
  const char* fn = "calibrate_cup";
  check_options(fn, options);
  check_experiments(fn, surfaces, experiments);
  initial.validate();
  const std::size_t n = experiments.size();

  CalibrationResult out;
  split(experiments, options.holdout_fraction, options.seed, out.train_indices, out.test_indices);

  // One pass with the initial cup. The miss, obstruction, hill and hole checks of the spring
  // model run before the force balance and do not involve c1 or c2 (docs/models.md §1, steps
  // 1-3), so
  // an experiment failing one of them fails for every (c1, c2): only the others are re-evaluated
  // during the search.
  const Predictor predictor(fn, surfaces, experiments, initial, options.num_threads);
  std::vector<std::size_t> all(n);
  std::iota(all.begin(), all.end(), std::size_t{0});
  std::vector<std::uint8_t> pred(n, 0), reason(n, 0);
  predictor.predict(initial, all, pred, &reason);
  const auto depends_on_constants = [&](std::size_t j) {
    const auto f = static_cast<SealFailure>(reason[j]);
    return f == SealFailure::None || f == SealFailure::Force;
  };

  Search search;
  search.predictor = &predictor;
  search.experiments = &experiments;
  search.cup = initial;
  search.n_train = static_cast<int>(out.train_indices.size());
  search.pred.assign(n, 0);
  for (std::size_t j : out.train_indices) {
    if (depends_on_constants(j)) {
      search.varying.push_back(j);
    } else {
      search.fixed_correct += !experiments[j].sealed;
    }
  }
  const std::vector<double> lb = {std::log(options.c1_min), std::log(options.c2_min)};
  const std::vector<double> ub = {std::log(options.c1_max), std::log(options.c2_max)};
  search.x0 = {std::log(initial.c1), std::log(initial.c2)};
  double d2_max = 0.0;
  for (double cx : {lb[0], ub[0]}) {
    for (double cy : {lb[1], ub[1]}) {
      d2_max = std::max(d2_max, (cx - search.x0[0]) * (cx - search.x0[0]) +
                                    (cy - search.x0[1]) * (cy - search.x0[1]));
    }
  }
  search.weight = 0.5 / (search.n_train * d2_max);

  // The initial constants (clamped into the box) are the first evaluation.
  const double c1_start = std::clamp(initial.c1, options.c1_min, options.c1_max);
  const double c2_start = std::clamp(initial.c2, options.c2_min, options.c2_max);
  const std::vector<double> start = {std::clamp(std::log(c1_start), lb[0], ub[0]),
                                     std::clamp(std::log(c2_start), lb[1], ub[1])};
  search.evaluate(start.data(), c1_start, c2_start);
  run_search(fn, nlopt::GN_DIRECT_L, "GN_DIRECT_L", options.global_evaluations, lb, ub, options,
             search, start);
  if (options.local_evaluations > 0) {
    // BOBYQA on a piecewise-constant objective often cannot improve the accuracy; it then walks
    // the plateau towards the initial constants (the tie-break penalty), which is what we want.
    const std::vector<double> from = {search.best_x[0], search.best_x[1]};
    run_search(fn, nlopt::LN_BOBYQA, "LN_BOBYQA", options.local_evaluations, lb, ub, options,
               search, from);
  }

  out.cup = initial;
  out.cup.c1 = search.best_c[0];
  out.cup.c2 = search.best_c[1];
  out.evaluations = search.evaluations;

  // Final predictions of every experiment with the fitted constants.
  std::vector<std::size_t> recheck;
  for (std::size_t j = 0; j < n; ++j) {
    if (depends_on_constants(j)) {
      recheck.push_back(j);
    } else {
      pred[j] = 0;
    }
  }
  predictor.predict(out.cup, recheck, pred, nullptr);
  out.predicted = pred;

  const auto metrics_of = [&](const std::vector<std::size_t>& idx) {
    std::vector<std::uint8_t> p, y;
    p.reserve(idx.size());
    y.reserve(idx.size());
    for (std::size_t j : idx) {
      p.push_back(pred[j]);
      y.push_back(experiments[j].sealed ? 1 : 0);
    }
    return classification_metrics(p, y);
  };
  out.train = metrics_of(out.train_indices);
  out.test = metrics_of(out.test_indices);
  out.objective = out.train.accuracy;
  return out;
}

}  // namespace mgn
