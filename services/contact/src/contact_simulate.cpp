// `hil contact simulate` as a library call: a run folder simulated from the rig's contact scene,
// optionally with hidden effects drawn by seed (and their truth JSON).
#include <hil/services/contact_simulate.hpp>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>

#include <hil/diagnose/contact_family.hpp>
#include <hil/error/error.hpp>
#include <hil/format/rig.hpp>
#include <hil/format/run.hpp>
#include <hil/models/contact.hpp>
#include <hil/format/output.hpp>

namespace hil::services::contact {

namespace cid = hil::contact_id;
namespace fs = std::filesystem;

namespace {

/// A field of the hidden-effects file as JSON: a number, an array, an array of rows, or an object.
nlohmann::json field_json(const hil::diagnose::TruthField& f) {
  if (!f.labels.empty()) {
    nlohmann::json o = nlohmann::json::object();
    for (std::size_t i = 0; i < f.labels.size(); ++i) o[f.labels[i]] = f.value(static_cast<Eigen::Index>(i), 0);
    return o;
  }
  if (f.value.size() == 1) return f.value(0, 0);
  auto row = [&](Eigen::Index r) {
    std::vector<double> v;
    for (Eigen::Index c = 0; c < f.value.cols(); ++c) v.push_back(f.value(r, c));
    return v;
  };
  if (f.value.cols() == 1) return std::vector<double>(f.value.data(), f.value.data() + f.value.size());
  nlohmann::json rows = nlohmann::json::array();
  for (Eigen::Index r = 0; r < f.value.rows(); ++r) rows.push_back(row(r));
  return rows;
}

/// The hidden truth of an injected simulation, for the test that checks the diagnosis: the
/// simulation's K, μ and true geometry, then every injectable effect's fields (the effects write
/// their own: hil::diagnose::truth_file_fields).
nlohmann::json effects_json(const hil::diagnose::Effects& e, const cid::ContactModel& m, unsigned seed) {
  nlohmann::json j;
  format::tag_format(j, "hidden_effects");
  j["effects"] = e.names();
  j["effect_seed"] = seed;
  j["K"] = m.K;
  j["mu"] = m.mu;
  j["geometric"] = e.geometric;
  for (const auto& f : hil::diagnose::truth_file_fields(e)) j[f.key] = field_json(f);
  return j;
}

/// An object of numbers by name.
nlohmann::json object_schema(const std::string& description) {
  return {{"type", "object"}, {"additionalProperties", {{"type", "number"}}}, {"description", description}};
}

/// A field's schema from its shape (TruthField's: number, array, array of rows, object).
nlohmann::json field_schema(const hil::diagnose::TruthField& f) {
  if (!f.labels.empty()) return object_schema(f.description);
  nlohmann::json s;
  if (f.value.size() == 1) {
    s = {{"type", "number"}};
  } else if (f.value.cols() == 1) {
    s = {{"type", "array"}, {"minItems", f.value.rows()}, {"maxItems", f.value.rows()}, {"items", {{"type", "number"}}}};
  } else {
    const nlohmann::json row = {{"type", "array"},
                                {"minItems", f.value.cols()},
                                {"maxItems", f.value.cols()},
                                {"items", {{"type", "number"}}}};
    s = {{"type", "array"}, {"minItems", f.value.rows()}, {"maxItems", f.value.rows()}, {"items", row}};
  }
  s["description"] = f.description;
  return s;
}

}  // namespace

nlohmann::json hidden_effects_schema() {
  nlohmann::json j;
  j["$schema"] = "https://json-schema.org/draft/2020-12/schema";
  j["$id"] = "https://hil.example/schemas/hil.hidden_effects.schema.json";
  j["title"] = "hil.hidden_effects";
  j["description"] =
      "Written by `hil contact simulate ... --inject EFFECT --truth-out OUT` (and by `hil demo` beside its run): the effects hidden in "
      "a simulated run with their drawn magnitudes, the truth a blind diagnosis is checked against. Generated from the effect "
      "registry by `hil contact truth-schema`. See docs/diagnosis.md.";
  j["type"] = "object";
  std::vector<std::string> required{"format", "format_version", "effects", "effect_seed", "K", "mu", "geometric"};
  std::vector<std::string> injectable;
  for (const hil::diagnose::Effect* e : hil::diagnose::registered_effects())
    if (e->contact() && e->contact()->injectable()) injectable.push_back(e->name());
  nlohmann::json p;
  p["format"] = {{"const", "hil.hidden_effects"}};
  p["format_version"] = {{"const", format::kJsonFormatVersion}};
  p["effects"] = {{"type", "array"},
                  {"minItems", 1},
                  {"uniqueItems", true},
                  {"items", {{"enum", injectable}}},
                  {"description", "the injected effects"}};
  p["effect_seed"] = {{"type", "integer"}, {"minimum", 0}, {"description", "seed of the effects' random magnitudes"}};
  p["K"] = {{"type", "number"}, {"description", "contact stiffness of the simulation, N/m"}};
  p["mu"] = {{"type", "number"}, {"minimum", 0}, {"description", "friction coefficient of the simulation"}};
  p["geometric"] = object_schema("true value of each geometric uncertainty by name (those absent stay at their design value), m or rad");
  for (const auto& f : hil::diagnose::truth_file_fields(hil::diagnose::Effects{})) {
    p[f.key] = field_schema(f);
    if (std::find(required.begin(), required.end(), f.key) == required.end()) required.push_back(f.key);
  }
  j["required"] = required;
  j["properties"] = p;
  j["additionalProperties"] = false;
  return j;
}

int simulate_run(const SimulateArgs& a) {
  const auto rig = format::load_rig(a.rig);
  const auto scene = models::scene_from_rig(rig);
  models::Truth truth;
  if (!a.truth.empty()) {
    truth = models::read_truth(a.truth, rig);
  } else {
    truth.model = models::model_from_rig(rig);
  }
  auto& s = truth.sensor;
  if (a.force_resolution >= 0) s.force_resolution_n = a.force_resolution;
  if (a.moment_resolution >= 0) s.moment_resolution_nm = a.moment_resolution;
  if (a.position_resolution >= 0) s.position_resolution_m = a.position_resolution;
  if (a.velocity_resolution >= 0) s.velocity_resolution_m_per_s = a.velocity_resolution;
  if (a.force_noise >= 0) s.force_noise_n = a.force_noise;
  if (a.moment_noise >= 0) s.moment_noise_nm = a.moment_noise;
  if (a.seed >= 0) s.seed = static_cast<unsigned>(a.seed);
  if (a.decimate < 1) throw error::FormatError({"command line", 0, 0, "--decimate"}, "must be at least 1");
  const Eigen::VectorXd x_true = models::uncertainty_vector(scene, truth.geometric, a.truth.empty() ? a.rig : a.truth);
  const auto traj = models::read_trajectory(a.trajectory);
  std::vector<cid::SimulatedSample> sim;
  if (a.inject.empty()) {
    if (!a.truth_out.empty()) throw error::FormatError({"command line", 0, 0, "--truth-out"}, "needs --inject");
    sim = cid::simulate(scene, truth.model, x_true, traj.kin, s);
  } else {
    hil::diagnose::Effects e;
    e.geometric = truth.geometric;
    for (const auto& name : a.inject) hil::diagnose::draw_effect(name, a.effect_seed, scene, e);
    sim = hil::diagnose::simulate_with_effects(scene, truth.model, e, traj.t, traj.kin, s);
    if (!a.truth_out.empty()) format::write_json(a.truth_out, effects_json(e, truth.model, a.effect_seed));
  }

  fs::create_directories(a.out);
  format::SampleTable table;
  std::size_t in_contact = 0;
  for (std::size_t i = 0; i < sim.size(); i += static_cast<std::size_t>(a.decimate)) {
    table.samples.push_back(models::sample({traj.t[i] - traj.t[0], sim[i].kin, sim[i].w_fp}));
    if (sim[i].contacts > 0) ++in_contact;
  }
  format::write_samples((fs::path(a.out) / "samples.csv").string(), table);
  const double rate = traj.t.size() > 1 ? static_cast<double>(traj.t.size() - 1) / (traj.t.back() - traj.t.front()) : 0.0;
  format::RunInfo info;
  info.rig = rig.name;
  info.start_time_utc = "2026-01-01T00:00:00.000Z";
  info.output_rate_hz = rate / a.decimate;
  info.sources.push_back({"simulation", "simulation", rate, "", {}});
  info.notes =
      fmt::format("Simulated by `hil contact simulate` from {} ({} samples at {:.4g} Hz, decimated by {}), truth {}. Sensor: "
                  "position resolution {} m, velocity resolution {} m/s, force resolution {} N (noise {} N), moment resolution {} N m "
                  "(noise {} N m), seed {}.",
                  a.trajectory, traj.t.size(), rate, a.decimate, a.truth.empty() ? "= the rig's nominal model" : a.truth,
                  s.position_resolution_m, s.velocity_resolution_m_per_s, s.force_resolution_n, s.force_noise_n, s.moment_resolution_nm,
                  s.moment_noise_nm, s.seed);
  if (!a.inject.empty()) info.notes += " Hidden effects injected (which ones is kept out of the run).";
  format::write_run_info((fs::path(a.out) / "run.yaml").string(), info);
  fs::copy_file(a.rig, fs::path(a.out) / "rig.yaml", fs::copy_options::overwrite_existing);
  format::human(format::is_stdout(a.truth_out))
      << fmt::format("wrote run {}: {} samples at {:.4g} Hz, {} in contact (K = {:.4g} N/m, mu = {:.3g})\n", a.out, table.samples.size(),
                     info.output_rate_hz, in_contact, truth.model.K, truth.model.mu);
  return 0;
}

}  // namespace hil::services::contact
