// Tests of the high-precision reference (reference/): I/O round trips and the
// inequalities of step 2. Table 1, Eq. (19), interpolation (Theorem 1, SISO and
// MIMO) and the step-6 failure are typed tests over the scalar, shared with
// fast/: tests/scalar_typed_test.cpp.
//
// Tolerances: the I/O bounds follow from the 40 significant digits written,
// derived where they are used.
#include "fdsid/reference/io.hpp"
#include "fdsid/reference/spectrum_id.hpp"
#include "test_support.hpp"

#include <boost/math/constants/constants.hpp>
#include <gtest/gtest.h>

#include <cstdio>
#include <string>
#include <tuple>
#include <vector>

namespace {

using namespace fdsid::reference;

using test::mat;

// Akçay (2011) Section 4 (McKelvey, Akçay & Ljung 1996), entries as printed.
Model paper_system() {
  Model model;
  model.A = mat({{"0.8876", "0.4494", "0", "0"},
                 {"-0.4494", "0.7978", "0", "0"},
                 {"0", "0", "-0.6129", "0.0645"},
                 {"0", "0", "-6.4516", "-0.7419"}});
  model.B = mat({{"0.2247"}, {"0.8989"}, {"0.0323"}, {"0.1290"}});
  model.C = mat({{"0.4719", "0.1124", "9.6774", "1.6129"}});
  model.D = mat({{"0.9626"}});
  return model;
}

// A 2x2, third-order system: poles 0.6 ± 0.3i and -0.5 (the same system as
// mimo_system in tests/scalar_typed_test.cpp, which checks Assumption 2.1).
Model mimo_system() {
  Model model;
  model.A = mat({{"0.6", "0.3", "0"}, {"-0.3", "0.6", "0.2"}, {"0", "0", "-0.5"}});
  model.B = mat({{"1", "0.2"}, {"0.3", "-0.5"}, {"0.2", "0.7"}});
  model.C = mat({{"0.4", "0.1", "0.3"}, {"-0.2", "0.5", "0.6"}});
  model.D = mat({{"1", "0.1"}, {"0.2", "0.8"}});
  return model;
}

Real max_abs(const MatrixC& X) {
  Real worst = 0;
  for (Eigen::Index i = 0; i < X.size(); ++i) worst = std::max(worst, abs(X.data()[i]));
  return worst;
}

// Theorem 1 (interpolation) on the Section 4 system, on the 2x2 system above
// and for Van Overschee's algorithm with small N − p − r: typed tests over the
// scalar, tests/scalar_typed_test.cpp.

// ---------------------------------------------------------------------------
// (5) I/O keeps the precision.

TEST(ReferenceIo, ModelJsonRoundTripKeepsThirtyDigits) {
  Model model = paper_system();
  model.B(0, 0) = Real(1) / 3;  // a number with no finite decimal expansion
  model.C(0, 1) = -boost::math::constants::pi<Real>() * Real("1e-7");
  const nlohmann::json j = model_to_json(model);
  // Every number is a decimal string with ≥ 30 significant digits.
  const std::string third = j["B"][0][0].get<std::string>();
  int significant = 0;
  for (char c : third.substr(0, third.find('e')))
    if (c >= '0' && c <= '9') ++significant;
  EXPECT_GE(significant, 30) << third;
  EXPECT_TRUE(j["sample_time"].is_string());
  // Through text and back: 40 significant digits, so the error is ≤ ½·10^{-39}
  // relative per entry (plus u for the parse); bound 1e-39 relative.
  const Model back = model_from_json(nlohmann::json::parse(j.dump()));
  for (const auto& [name, X, Y] : {std::tuple<const char*, const MatrixR&, const MatrixR&>{"A", model.A, back.A},
                                   {"B", model.B, back.B},
                                   {"C", model.C, back.C},
                                   {"D", model.D, back.D}}) {
    ASSERT_EQ(X.rows(), Y.rows()) << name;
    ASSERT_EQ(X.cols(), Y.cols()) << name;
    for (Eigen::Index i = 0; i < X.size(); ++i)
      EXPECT_LE(abs(X.data()[i] - Y.data()[i]), Real("1e-39") * abs(X.data()[i])) << name;
  }
  // Decimal strings are exact: "0.8876" is 0.8876, not the double 0.8876.
  EXPECT_EQ(back.A(0, 0), Real("0.8876"));
  EXPECT_NE(Real("0.8876"), Real(0.8876));
}

TEST(ReferenceIo, JsonNumbersAndBadEntries) {
  // A JSON number with ≤ 15 significant digits is recovered exactly from its
  // shortest round-trip decimal; longer ones carry the double's error.
  nlohmann::json j = nlohmann::json::parse(
      R"({"domain": "discrete", "sample_time": 1.0, "A": [[0.8876, 2]], "B": [[0.2247], [-1e-3]],
          "C": [["+.5", "1.5e-2"]], "D": [[0.12345678901234567]]})");
  j["A"] = nlohmann::json::parse("[[0.8876, 2], [3, -0.4494]]");
  const Model model = model_from_json(j);
  EXPECT_EQ(model.A(0, 0), Real("0.8876"));
  EXPECT_EQ(model.A(1, 1), Real("-0.4494"));
  EXPECT_EQ(model.B(1, 0), Real("-0.001"));
  EXPECT_EQ(model.C(0, 0), Real("0.5"));
  EXPECT_EQ(model.C(0, 1), Real("0.015"));
  EXPECT_NE(model.D(0, 0), Real("0.12345678901234567"));               // binary error …
  // … of a double: |x − fl(x)| ≤ ½ ulp and the shortest decimal of fl(x) is
  // within ½ ulp of it, so ≤ 1 ulp = 2^-56 ≈ 1.39e-17 at 0.12.
  EXPECT_LE(abs(model.D(0, 0) - Real("0.12345678901234567")), Real("1.39e-17"));

  for (const char* bad : {R"("abc")", R"("1e")", R"("nan")", R"("0x10")", "null", R"("")"}) {
    nlohmann::json broken = j;
    broken["C"][0][1] = nlohmann::json::parse(bad);
    try {
      model_from_json(broken);
      ADD_FAILURE() << "accepted C entry " << bad;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("\"C\" row 1 column 2"), std::string::npos) << e.what();
    }
  }
  nlohmann::json wrong_shape = j;
  wrong_shape["B"] = nlohmann::json::parse("[[1]]");
  EXPECT_THROW(model_from_json(wrong_shape), InputError);
}

TEST(ReferenceIo, SpectrumCsvRoundTripAndErrors) {
  const Spectrum spectrum = sample_spectrum(mimo_system(), 4);
  const std::string path = ::testing::TempDir() + "reference_spectrum.csv";
  write_spectrum_csv(spectrum, path);
  const Spectrum back = read_spectrum_csv(path);
  ASSERT_EQ(back.m, 2);
  ASSERT_EQ(back.M, 4);
  // 40 significant digits written: ≤ 1e-39 relative per entry.
  for (int k = 0; k <= 4; ++k)
    EXPECT_LE(max_abs(MatrixC(back.S[k] - spectrum.S[k])), Real("1e-39") * max_abs(spectrum.S[k]));

  auto expect_error = [&](const std::string& text, const std::string& fragment) {
    const std::string bad = ::testing::TempDir() + "reference_bad.csv";
    {
      std::FILE* f = std::fopen(bad.c_str(), "w");
      ASSERT_NE(f, nullptr);
      std::fputs(text.c_str(), f);
      std::fclose(f);
    }
    try {
      read_spectrum_csv(bad);
      ADD_FAILURE() << "accepted:\n" << text;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(bad + fragment), std::string::npos) << e.what();
    }
  };
  expect_error("omega,S_re,S_im\n0,1,0\n1.5707963267948966,x,0\n3.141592653589793,1,0\n",
               ":3: column S_re: not a decimal number");
  expect_error("omega,S_re,S_im\n0,1,0\n1.6,1,0\n3.141592653589793,1,0\n", ":3: omega =");
  expect_error("omega,S_re,S_im\n0,1,0\n3.141592653589793,1\n", ":3: 2 cells");
  expect_error("omega,S_re\n0,1\n", ":1:");
  expect_error("omega,S_re,S_im\n0,1,0\n", ":2: need at least 2 samples");
  // Grid points written with 17 digits (doubles) are accepted (1e-9·π tolerance).
  const std::string good = ::testing::TempDir() + "reference_good.csv";
  {
    std::FILE* f = std::fopen(good.c_str(), "w");
    ASSERT_NE(f, nullptr);
    std::fputs("omega,S_re,S_im\r\n0,2,0\r\n1.5707963267948966,1.5,0\r\n3.1415926535897931,1,0\r\n", f);
    std::fclose(f);
  }
  EXPECT_EQ(read_spectrum_csv(good).M, 2);
}

TEST(ReferenceArguments, InequalitiesOfStep2AreChecked) {
  const Spectrum spectrum = sample_spectrum(paper_system(), 8);  // N = 16
  EXPECT_THROW(identify_spectrum(spectrum, 4, 8, 8), InputError);   // p > 2n violated
  EXPECT_THROW(identify_spectrum(spectrum, 4, 9, 7), InputError);   // r ≥ 2n violated
  EXPECT_THROW(identify_spectrum(spectrum, 2, 9, 8), InputError);   // p + r ≤ N violated
  EXPECT_THROW(akcay_Y(spectrum, 10, 7), InputError);
  Spectrum short_data = spectrum;
  short_data.S.pop_back();
  EXPECT_THROW(identify_spectrum(short_data, 2, 5, 4), InputError);
}

}  // namespace
