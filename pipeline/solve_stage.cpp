#include "pipeline/solve_stage.hpp"

#include <cstdio>
#include <sstream>

#include "geometry/hierarchical/hierarchical.hpp"
#include "pipeline/job.hpp"

namespace lambert {

void set_memory_limit(SolveOptions& o, const std::string& max_memory) {
  const auto limit = job_memory_limit(max_memory);
  o.memory_limit = limit ? limit->bytes : 0.0;
  o.memory_limit_source = limit ? limit->source : "";
}

const char* channel_name(int channel) {
  static const char* kNames[] = {"R", "G", "B"};
  return kNames[channel];
}

std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string out = "\"";
  for (char c : s) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + "\"";
}

std::string csv_number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

namespace {
// A part of the imbalance relative to the emitted power (absolute when nothing is emitted,
// as relative_imbalance is).
double relative(const EnergyBalance& e, double part) {
  return e.emitted > 0.0 ? part / e.emitted : part;
}
}  // namespace

Json energy_json(const EnergyBalance& e) {
  return {{"emitted", e.emitted},
          {"absorbed", e.absorbed},
          {"escaped", e.escaped},
          {"relative_imbalance", e.relative_imbalance},
          {"residual_part", e.residual_part},
          {"non_reciprocity_part", e.non_reciprocity_part},
          {"relative_residual_part", relative(e, e.residual_part)},
          {"relative_non_reciprocity_part", relative(e, e.non_reciprocity_part)}};
}

Json surface_averages_json(const std::vector<SurfaceRadiosity>& surfaces) {
  Json list = Json::array();
  for (const auto& s : surfaces)
    list.push_back({{"name", s.name},
                    {"area", s.area},
                    {"patches", s.patches},
                    {"average_radiosity", {s.average[0], s.average[1], s.average[2]}}});
  return list;
}

std::string energy_split_text(const EnergyBalance& e) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "residual part %.2e, non-reciprocity part %.2e",
                relative(e, e.residual_part), relative(e, e.non_reciprocity_part));
  return buf;
}

}  // namespace lambert
