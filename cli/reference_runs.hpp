#pragma once
// The reference's runs behind the high-precision subcommands (check, certify,
// identify-* --precision high): private to cli/, the only header of the
// command layer that sees the multiprecision types.
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "fdsid/model.hpp"
#include "fdsid/reference/frf_id.hpp"
#include "fdsid/reference/spectrum_id.hpp"
#include "high_precision.hpp"

namespace fdsid::cli {

/// The reference's value of a double, exactly (17 significant digits identify it).
reference::Real exact(double x);

/// The perturbations of check's tolerance for an unperturbed result at p, r, M.
using PerturbationsFor =
    std::function<std::vector<reference::BackwardPerturbation>(const reference::Result&, int, int, int)>;

/// check's rule (workflow.hpp, set_oracle_tolerances): the backward errors of a
/// correct double implementation of Algorithm 1 (oracle_backward_errors) in
/// three random directions (seeds 1, 2, 3).
PerturbationsFor spectrum_perturbations(bool van_overschee);

/// Akçay (2011) Algorithm 1 in the reference on a spectrum CSV (checked by
/// fast/'s reader first, for its one-line messages); p, r = 0 take the
/// documented default and are set; m, M are set. With `perturbations_for`:
/// also the perturbed reruns into `perturbed` (steps 1-2 shared; a rerun whose
/// step fails is left out). Errors: Error(Input) for bad data, Error(Numerical)
/// when a step fails.
reference::Result run_reference(const std::string& data_path, int order, int& p, int& r, bool van_overschee,
                                Extension ext, int& m, int& M, const PerturbationsFor* perturbations_for = nullptr,
                                std::vector<reference::Result>* perturbed = nullptr);

/// Pintelon (2002) in the reference for the request (FRF file or records with
/// Section 5's treatment); its errors turned into the library's typed errors.
/// `perturbation` > 0: reference::FrfOptions::backward_perturbation (check's tolerance).
reference::FrfResult reference_frf(const FrfHighRequest& q, const reference::Real& perturbation = 0,
                                   unsigned seed = 1);

/// The identified model's JSON, every number a decimal string of `digits` digits.
nlohmann::json frf_high_json(const reference::FrfResult& res, const FrfHighRequest& q, const std::string& where,
                             const std::string& note, int digits = 40);

/// The reference again at the request's settings with Z and C_Y moved by the
/// backward error of a correct double implementation (frf_backward_error) in
/// three random directions: FrfTolerance::perturbed. Discrete models get
/// `sample_time`.
std::vector<StateSpace> frf_perturbed_models(const FrfHighRequest& q, double backward_error, double sample_time);

/// "high (50-digit binary floating point, Boost.Multiprecision cpp_bin_float<50>)", with the build's digits.
std::string precision_label();

}  // namespace fdsid::cli
