#include <hil/diagnose/effect.hpp>

#include <algorithm>
#include <array>
#include <mutex>
#include <stdexcept>
#include <utility>

namespace hil::diagnose {

namespace {

struct Registry {
  std::mutex mutex;
  std::vector<std::shared_ptr<const Effect>> effects;
  std::array<std::vector<std::string>, 3> names;  ///< per FamilyKind

  Registry() {
    auto builtin = builtin_effects();
    std::sort(builtin.begin(), builtin.end(), [](const auto& a, const auto& b) {
      if (!a || !b) return static_cast<bool>(b);  // add() refuses the null one
      return std::make_pair(a->list_order(), a->name()) < std::make_pair(b->list_order(), b->name());
    });
    for (auto& e : builtin) add(std::move(e));
  }

  void add(std::shared_ptr<const Effect> e) {
    if (!e) throw std::invalid_argument("register_effect: no effect");
    const std::string n = e->name();
    for (const auto& x : effects)
      if (x->name() == n) throw std::invalid_argument("register_effect: '" + n + "' is registered already");
    for (const FamilyKind f : {FamilyKind::contact, FamilyKind::deflection, FamilyKind::stiffness})
      if (e->extends(f)) names[static_cast<std::size_t>(f)].push_back(n);
    effects.push_back(std::move(e));
  }
};

// Built on first use, so a test fixture's static registration finds the built-in effects first.
Registry& registry() {
  static Registry r;
  return r;
}

}  // namespace

bool register_effect(std::shared_ptr<const Effect> effect) {
  auto& r = registry();
  const std::lock_guard<std::mutex> lock(r.mutex);
  r.add(std::move(effect));
  return true;
}

const Effect* find_effect(const std::string& name) {
  auto& r = registry();
  const std::lock_guard<std::mutex> lock(r.mutex);
  for (const auto& e : r.effects)
    if (e->name() == name) return e.get();
  return nullptr;
}

std::vector<const Effect*> registered_effects() {
  auto& r = registry();
  const std::lock_guard<std::mutex> lock(r.mutex);
  std::vector<const Effect*> out;
  for (const auto& e : r.effects) out.push_back(e.get());
  return out;
}

const std::vector<std::string>& effect_names(FamilyKind family) { return registry().names[static_cast<std::size_t>(family)]; }

int default_cv_offsets(const std::vector<std::string>& candidates) {
  int offsets = 1;
  for (const auto& c : candidates)
    if (const Effect* e = find_effect(c)) offsets = std::max(offsets, e->cv_offsets());
  return offsets;
}

std::string separating_experiment(const std::string& a, const std::string& b) {
  for (const auto& [x, y] : {std::pair{a, b}, std::pair{b, a}})
    if (const Effect* e = find_effect(x))
      if (auto s = e->separating_experiment(y); !s.empty()) return s;
  return "a run whose motion excites " + a + " and " + b + " differently (other speeds, loads or directions than this one)";
}

}  // namespace hil::diagnose
