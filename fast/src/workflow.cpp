#include "fdsid/workflow.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "fdsid/error.hpp"

namespace fdsid {

void require_sample_subspace_periods(const RecordMeta& meta, const std::string& meta_path) {
  if (meta.periods < 4)
    throw Error(ErrorKind::Input, meta_path + " field \"periods\"",
                "M = " + std::to_string(meta.periods) +
                    " periods: the sample-subspace estimates of B and D need M >= 4, those of A and C "
                    "M >= 2 (Pintelon 2002 Theorem 2)");
}

FrfRun identify_frf_records(const SampleStatistics& stats, const FrfOptions& o, RecordTreatment treatment,
                            EivVariance eiv_variance, double min_input_snr) {
  FrfRun run;
  switch (treatment) {
    case RecordTreatment::ErrorsInVariables:
      run.data = errors_in_variables(stats, nullptr, min_input_snr, &run.dropped_lines);
      run.result = identify_frf(run.data, o);
      if (eiv_variance == EivVariance::Model) {
        run.data = errors_in_variables(stats, &run.result.model, min_input_snr, &run.dropped_lines);
        FrfOptions second = o;
        second.order = run.result.order;
        second.r = run.result.r;
        run.result = identify_frf(run.data, second);
      }
      break;
    case RecordTreatment::Improper:
      run.data = swap_input_output(stats, min_input_snr, &run.dropped_lines);
      run.result = identify_frf(run.data, o);
      break;
    case RecordTreatment::Plain:
      run.data = stats.data;
      run.result = identify_frf(run.data, o);
      break;
  }
  if (run.data.domain == Domain::Discrete) run.result.model.sample_time = run.data.sample_time;
  return run;
}

OrderAndR select_order_and_r(const FrfData& data, const FrfOptions& options) {
  if (options.order > 0 && options.r > 0) return {options.order, options.r};
  const FrfResult sel = identify_frf(data, options);
  return {sel.order, sel.r};
}

std::string frf_method_name(Domain domain, ContinuousMethod method) {
  return domain == Domain::Discrete ? std::string("pintelon2002-alg1")
                                    : std::string("pintelon2002-alg2-") + to_string(method);
}

void require_spectrum_model(const StateSpace& model, const std::string& where) {
  if (model.order() > 0) {
    const double rho = poles(model).cwiseAbs().maxCoeff();
    if (!(rho < 1.0))
      throw Error(ErrorKind::Input, where,
                  "A has a pole of modulus " + std::to_string(rho) +
                      " (not inside the unit circle): the power spectrum of an unstable model is not defined");
  }
  if (model.inputs() != model.outputs())
    throw Error(ErrorKind::Input, where, "a power spectrum needs a square model (as many inputs as outputs)");
}

double std_ratio_standard_error(int runs) {
  if (runs <= 0) return std::numeric_limits<double>::infinity();
  return std::sqrt(2.0) / std::sqrt(2.0 * runs);
}

double eigenvalue_condition_number(const Eigen::MatrixXd& A) {
  double kappa = 1;
  if (A.rows() == 0) return kappa;
  Eigen::EigenSolver<Eigen::MatrixXd> es(A);
  const Eigen::MatrixXcd V = es.eigenvectors(), W = V.inverse();
  for (Eigen::Index i = 0; i < A.rows(); ++i) kappa = std::max(kappa, V.col(i).norm() * W.row(i).norm());
  return kappa;
}

bool OracleCheck::agree() const {
  const ModelComparison& c = comparison;
  return orders_agree() && c.pole_distance <= pole_tolerance && c.spectrum_error <= spectrum_tolerance &&
         c.markov_error <= pole_tolerance;
}

void set_oracle_tolerances(OracleCheck& check, const Eigen::MatrixXd& reference_A, int m, int N,
                           double sigma1_over_sigma2n, double tolerance) {
  check.tolerance_given = tolerance > 0;
  check.spectrum_tolerance =
      tolerance > 0 ? tolerance : double_precision_spectrum_tolerance(check.p, check.r, m, N, sigma1_over_sigma2n);
  check.pole_tolerance =
      tolerance > 0 ? tolerance : eigenvalue_condition_number(reference_A) * check.spectrum_tolerance;
}

}  // namespace fdsid
