#include "io/ff_settings.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace lambert {
namespace {

using Setting = FormFactorSetting;

// Options under which every row with a key is stored (the analytic estimator: tol; extended
// form factors: specular_*; a medium: medium_*), every value off its default.
FormFactorOptions every_row_stored() {
  FormFactorOptions o;
  o.estimator = "analytic";
  o.pair.samples = 77;
  o.gather.rays = 4321;
  o.run.seed = std::numeric_limits<std::uint64_t>::max();  // all 64 bits survive
  o.threshold = 1.0 / 3.0;                                 // %.17g reads back exactly
  o.hemicube.resolution = 96;
  o.analytic.tol = 2.5e-7;
  o.reciprocity = "average";
  o.specular.depth = 3;
  o.specular.rays = 333;
  o.contents.extended = true;
  o.contents.medium_zones = 12;
  o.contents.medium_extinction = 0x0123456789abcdefull;
  o.contents.medium_rays = 55;
  o.contents.transmittance_samples = 6;
  return o;
}

// Every row that applies to `a` stores and reports the same for `b`, and the reports agree.
void expect_same_rows(const FormFactorOptions& a, const FormFactorOptions& b,
                      const std::string& what) {
  for (const Setting& s : form_factor_settings()) {
    if (!setting_applies(s, a)) continue;
    EXPECT_EQ(s.text(a), s.text(b)) << s.key << s.name << " after " << what;
    EXPECT_EQ(s.value(a), s.value(b)) << s.key << s.name << " after " << what;
  }
  EXPECT_EQ(ff_settings_report(a), ff_settings_report(b)) << what;
}

// Values in each row's range, its limits included.
std::vector<std::string> accepted_values(const Setting& s) {
  switch (s.kind) {
    case Setting::Kind::Word:
      return s.choices.empty() ? std::vector<std::string>{"hybrid"} : s.choices;
    case Setting::Kind::Integer:
      return {std::to_string(s.min), std::to_string(s.min + 1), std::to_string(s.max)};
    case Setting::Kind::Unsigned:
      return {"0", "18446744073709551615"};
    case Setting::Kind::Real: {
      std::vector<std::string> v = {"4.9406564584124654e-324", "0.10000000000000001",
                                    "1.7976931348623157e+308"};
      if (!s.positive) v.insert(v.end(), {"0", "-2.5"});
      return v;
    }
    case Setting::Kind::Flag:
      return {"0", "1"};
  }
  return {};
}

// Values each row refuses: outside its range, or not a value of its kind.
std::vector<std::string> refused_values(const Setting& s) {
  switch (s.kind) {
    case Setting::Kind::Word:
      return s.choices.empty() ? std::vector<std::string>{""}
                               : std::vector<std::string>{"", "auto", "bogus"};
    case Setting::Kind::Integer:
      return {std::to_string(s.min - 1), std::to_string(s.max + 1), "", "1.5", "x"};
    case Setting::Kind::Unsigned:
      return {"-1", "18446744073709551616", "", "x"};
    case Setting::Kind::Real: {
      std::vector<std::string> v = {"inf", "nan", "1e400", "", "x"};
      if (s.positive) v.insert(v.end(), {"0", "-1e-300"});
      return v;
    }
    case Setting::Kind::Flag:
      return {"2", "true", ""};
  }
  return {};
}

}  // namespace

TEST(FormFactorSettings, EveryStoredSettingReadsBackExactly) {
  const FormFactorOptions o = every_row_stored();
  FormFactorOptions back;
  ASSERT_TRUE(parse_ff_settings(format_ff_settings(o) + " patches=24 max_edge=0.5", back));
  EXPECT_EQ(back.estimator, o.estimator);
  EXPECT_EQ(back.pair.samples, o.pair.samples);
  EXPECT_EQ(back.gather.rays, o.gather.rays);
  EXPECT_EQ(back.run.seed, o.run.seed);
  EXPECT_EQ(back.threshold, o.threshold);
  EXPECT_EQ(back.hemicube.resolution, o.hemicube.resolution);
  EXPECT_EQ(back.analytic.tol, o.analytic.tol);
  EXPECT_EQ(back.reciprocity, o.reciprocity);
  EXPECT_EQ(back.specular.depth, o.specular.depth);
  EXPECT_EQ(back.specular.rays, o.specular.rays);
  EXPECT_EQ(back.contents.extended, o.contents.extended);
  EXPECT_EQ(back.contents.medium_zones, o.contents.medium_zones);
  EXPECT_EQ(back.contents.medium_extinction, o.contents.medium_extinction);
  EXPECT_EQ(back.contents.medium_rays, o.contents.medium_rays);
  EXPECT_EQ(back.contents.transmittance_samples, o.contents.transmittance_samples);
  expect_same_rows(o, back, "the round trip");
}

TEST(FormFactorSettings, EveryRowRoundTripsAcrossItsRange) {
  for (const Setting& s : form_factor_settings()) {
    if (*s.key == '\0') continue;  // reported only
    for (const std::string& v : accepted_values(s)) {
      FormFactorOptions o = every_row_stored();
      // A row stored only with its own estimators (--target-stderr: mc, hybrid): one of them.
      if (!s.estimators.empty() &&
          std::find(s.estimators.begin(), s.estimators.end(), o.estimator) == s.estimators.end())
        o.estimator = s.estimators.front();
      ASSERT_TRUE(s.read(s, v, o)) << s.key << "=" << v;
      FormFactorOptions back;
      ASSERT_TRUE(parse_ff_settings(format_ff_settings(o), back)) << format_ff_settings(o);
      EXPECT_EQ(s.text(back), v) << s.key;
      expect_same_rows(o, back, std::string(s.key) + "=" + v);
    }
  }
}

TEST(FormFactorSettings, EveryRowRefusesValuesOutsideItsRange) {
  const std::string stored = format_ff_settings(every_row_stored());
  for (const Setting& s : form_factor_settings()) {
    if (*s.key == '\0') continue;
    for (const std::string& v : refused_values(s)) {
      // A repeated key: the last of a required one counts, a bad optional one refuses.
      const std::string text = stored + " " + s.key + "=" + v;
      FormFactorOptions untouched;
      untouched.estimator = "keep";
      EXPECT_FALSE(parse_ff_settings(text, untouched)) << text;
      EXPECT_EQ(untouched.estimator, "keep") << text;
      EXPECT_EQ(untouched.reciprocity, "auto") << text;
    }
  }
}

TEST(FormFactorSettings, TextIsTheFormatSavedFilesHold) {
  FormFactorOptions o;
  o.estimator = "hybrid";
  o.reciprocity = "none";
  EXPECT_EQ(format_ff_settings(o),
            "estimator=hybrid samples=32 rays=1024 seed=1 threshold=0 hemicube_res=128 "
            "reciprocity=none symmetrize=0 target_stderr=0");
  EXPECT_EQ(format_ff_settings(every_row_stored()),
            "estimator=analytic samples=77 rays=4321 seed=18446744073709551615 "
            "threshold=0.33333333333333331 hemicube_res=96 reciprocity=average symmetrize=1 "
            "specular_depth=3 specular_rays=333 tol=2.4999999999999999e-07 medium_zones=12 "
            "medium_extinction=81985529216486895 medium_rays=55 transmittance_samples=6");
}

TEST(FormFactorSettings, EveryEstimatorParameterHasTheRowItsDeclarationGives) {
  for (const DeclaredEstimatorParam& d : estimator_params()) {
    const EstimatorParam& p = d.param;
    SCOPED_TRACE(p.option);
    int rows = 0;
    for (const Setting& s : form_factor_settings()) {
      if (s.param != p.option) continue;
      ++rows;
      EXPECT_EQ(s.key, p.key.empty() ? p.keyword : p.key);
      EXPECT_EQ(s.name, p.report.empty() ? p.keyword : p.report);
      EXPECT_EQ(s.estimators, d.estimators);
      EXPECT_EQ(s.kind, p.integer ? Setting::Kind::Integer : Setting::Kind::Real);
      // Stored for every estimator (the first ones'), or for those that read it.
      FormFactorOptions o;
      o.estimator = d.estimators.front();
      EXPECT_TRUE(setting_applies(s, o));
      o.estimator = "no such estimator";
      EXPECT_EQ(setting_applies(s, o), p.stored_always);
    }
    EXPECT_EQ(rows, 1);
  }
}

TEST(FormFactorSettings, ReportNamesEverySettingAndNullsWhatDoesNotApply) {
  FormFactorOptions o = every_row_stored();
  o.estimator_requested = "auto";
  EXPECT_EQ(ff_settings_report(o).dump(),
            R"({"estimator":"analytic","estimator_requested":"auto","samples":77,)"
            R"("rays_per_patch":4321,"seed":18446744073709551615,"threshold":0.3333333333333333,)"
            R"("hemicube_resolution":96,"tol":2.5e-07,"reciprocity":"average","symmetrize":true,)"
            R"("extended":true,"specular_depth":3,"specular_rays":333,"target_stderr":null})");
  FormFactorOptions plain;
  plain.estimator = "gather";
  plain.reciprocity = "average";
  EXPECT_EQ(ff_settings_report(plain).dump(),
            R"({"estimator":"gather","estimator_requested":null,"samples":32,)"
            R"("rays_per_patch":1024,"seed":1,"threshold":0.0,"hemicube_resolution":128,)"
            R"("tol":null,"reciprocity":"average","symmetrize":true,"extended":false,)"
            R"("specular_depth":null,"specular_rays":null,"target_stderr":null})");
  // A loaded F without settings: its estimator is unknown, and so is every setting.
  FormFactorOptions unknown;
  unknown.estimator.clear();
  const Json report = ff_settings_report(unknown);
  for (const auto& [name, value] : report.items()) EXPECT_TRUE(value.is_null()) << name;
}

TEST(FormFactorSettings, ReciprocityKeyWinsOverTheLegacySymmetrizeInEitherOrder) {
  const std::string head = "estimator=hemicube samples=32 seed=1 threshold=0 ";
  for (const char* tail : {"symmetrize=1 reciprocity=none", "reciprocity=none symmetrize=1"}) {
    FormFactorOptions o;
    ASSERT_TRUE(parse_ff_settings(head + tail, o)) << tail;
    EXPECT_EQ(o.reciprocity, "none") << tail;
  }
  FormFactorOptions o;
  ASSERT_TRUE(parse_ff_settings(head + "symmetrize=1", o));
  EXPECT_EQ(o.reciprocity, "average");
  // Still checked where it yields.
  EXPECT_FALSE(parse_ff_settings(head + "reciprocity=none symmetrize=2", o));
  // Neither key: files before them were made without averaging.
  ASSERT_TRUE(parse_ff_settings(head, o));
  EXPECT_EQ(o.reciprocity, "none");
}

}  // namespace lambert
