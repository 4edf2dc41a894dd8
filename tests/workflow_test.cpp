// The tool's procedures as library calls (fdsid/workflow.hpp) and the JSON of
// the tool's results (fdsid/json.hpp): the rules fdsid used to apply in cli/.
#include <gtest/gtest.h>

#include <cmath>

#include "fdsid/error.hpp"
#include "fdsid/json.hpp"
#include "fdsid/workflow.hpp"

namespace fdsid {
namespace {

StateSpace first_order(double a) {
  StateSpace m;
  m.A = Eigen::MatrixXd::Constant(1, 1, a);
  m.B = Eigen::MatrixXd::Constant(1, 1, 1.0);
  m.C = Eigen::MatrixXd::Constant(1, 1, 1.0);
  m.D = Eigen::MatrixXd::Constant(1, 1, 1.0);
  return m;
}

TEST(Workflow, SampleSubspaceNeedsFourPeriods) {
  RecordMeta meta;
  meta.periods = 3;
  try {
    require_sample_subspace_periods(meta, "m.json");
    FAIL() << "M = 3 accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.where(), "m.json field \"periods\"");
    EXPECT_NE(e.message().find("M >= 4"), std::string::npos);
  }
  meta.periods = 4;
  EXPECT_NO_THROW(require_sample_subspace_periods(meta, "m.json"));
}

TEST(Workflow, SpectrumModelMustBeStableAndSquare) {
  EXPECT_NO_THROW(require_spectrum_model(first_order(0.5), "m.json"));
  EXPECT_THROW(require_spectrum_model(first_order(1.0), "m.json"), Error);
  EXPECT_THROW(require_spectrum_model(first_order(-1.5), "m.json"), Error);
  StateSpace wide = first_order(0.5);
  wide.B = Eigen::MatrixXd::Ones(1, 2);
  wide.D = Eigen::MatrixXd::Ones(1, 2);
  EXPECT_THROW(require_spectrum_model(wide, "m.json"), Error);
}

TEST(Workflow, StdRatioStandardError) {
  // sqrt(2) / sqrt(2 N): 0.1 at N = 100.
  EXPECT_DOUBLE_EQ(std_ratio_standard_error(100), 0.1);
  EXPECT_TRUE(std::isinf(std_ratio_standard_error(0)));
}

TEST(Workflow, EigenvalueConditionNumber) {
  EXPECT_DOUBLE_EQ(eigenvalue_condition_number(Eigen::MatrixXd::Identity(3, 3)), 1.0);
  Eigen::MatrixXd A(2, 2);
  A << 0.5, 100, 0, 0.6;  // nearly parallel eigenvectors: badly conditioned
  EXPECT_GT(eigenvalue_condition_number(A), 100.0);
}

TEST(Workflow, FrfMethodNames) {
  EXPECT_EQ(frf_method_name(Domain::Discrete, ContinuousMethod::Orthogonal), "pintelon2002-alg1");
  EXPECT_EQ(frf_method_name(Domain::Continuous, ContinuousMethod::Bilinear), "pintelon2002-alg2-bilinear");
  EXPECT_EQ(frf_method_name(Domain::Continuous, ContinuousMethod::Orthogonal), "pintelon2002-alg2-orthogonal");
}

TEST(Workflow, GivenOrderAndRAreKept) {
  FrfOptions o;
  o.order = 3;
  o.r = 7;
  const OrderAndR s = select_order_and_r(FrfData{}, o);  // no identification needed
  EXPECT_EQ(s.order, 3);
  EXPECT_EQ(s.r, 7);
}

TEST(Json, FrfSourceNamesItsTreatment) {
  FrfSource s;
  s.frf_path = "g.csv";
  EXPECT_EQ(to_json(s).dump(), R"j({"frf":"g.csv","variance":"none (unit weights)"})j");
  FrfSource r;
  r.data_path = "rec.csv";
  r.meta_path = "rec.meta.json";
  r.periods = 6;
  r.treatment = RecordTreatment::ErrorsInVariables;
  r.eiv_variance = EivVariance::Model;
  r.dropped_lines = 2;
  const nlohmann::json j = to_json(r);
  EXPECT_EQ(j["errors_in_variables"]["variance"], "Eq. (31) at the first-pass model");
  EXPECT_EQ(j["errors_in_variables"]["dropped_lines"], 2);
  EXPECT_EQ(j["periods"], 6);
  EXPECT_FALSE(j.contains("improper"));
}

TEST(Json, OracleCheckVerdict) {
  OracleCheck k;
  k.comparison.candidate_order = k.comparison.reference_order = 2;
  k.comparison.pole_distance = 1e-9;
  k.comparison.spectrum_error = 1e-10;
  k.comparison.markov_error = 1e-9;
  set_oracle_tolerances(k, first_order(0.5), {}, 1e-8);
  EXPECT_TRUE(k.agree());
  EXPECT_EQ(to_json(k)["tolerance"]["rule"], "given by --tolerance");
  // Per quantity: distance, tolerance, ratio (issue 13: the tightness of the oracle).
  const nlohmann::json q = to_json(k)["quantities"];
  ASSERT_EQ(q.size(), 5u);
  EXPECT_EQ(q[0]["quantity"], "poles");
  EXPECT_DOUBLE_EQ(q[0]["ratio"].get<double>(), 1e-9 / 1e-8);
  EXPECT_EQ(q[1]["quantity"], "spectrum");
  EXPECT_DOUBLE_EQ(q[1]["ratio"].get<double>(), 1e-10 / 1e-8);
  k.comparison.reference_order = 3;
  EXPECT_FALSE(k.agree());
  EXPECT_EQ(to_json(k)["agree"], false);
}

}  // namespace
}  // namespace fdsid
