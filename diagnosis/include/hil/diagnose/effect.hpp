#pragma once
/// \file A candidate effect of the diagnosis and the registry the families, the CLI's list and help,
/// the hidden-effect generator and the docs' table take their effects from (issue 26, item 2).
///
/// An effect is one file (diagnosis/src/effects/<name>.cpp, or a test fixture): its name, what it
/// means, which model families have it, what its presence asks of the cross-validation, and, for the
/// contact family, its model (ContactEffect, contact_effect.hpp: parameters with units and bounds,
/// design columns, report lines, physical-validity check, and its draw for injection). Pure numerics.
#include <memory>
#include <string>
#include <vector>

namespace hil::diagnose {

/// The model families an effect can extend.
enum class FamilyKind { contact, deflection, stiffness };

class ContactEffect;

class Effect {
 public:
  virtual ~Effect() = default;
  virtual std::string name() const = 0;
  /// One sentence on what the effect means physically (the summary's "cause: x — ...").
  virtual std::string description() const = 0;
  virtual bool extends(FamilyKind family) const = 0;
  /// The grid offsets of repeated blocked CV this effect asks for when it is a candidate (the
  /// default CvOptions::offsets is the largest over the candidates): an effect whose events are
  /// located from the data cannot predict one inside a held-out block, so a single grid's verdict
  /// depends on where its edges fall (docs/diagnosis.md, "Repeated blocked CV").
  virtual int cv_offsets() const { return 1; }
  /// Why it asks for more than one offset (a note of the diagnosis; empty with one).
  virtual std::string cv_offsets_reason() const { return ""; }
  /// Its model locates events from the data (ModelFamily::located_events), reported with intervals.
  virtual bool locates_events() const { return false; }
  /// Its model in the contact family (nullptr: not a contact effect).
  virtual const ContactEffect* contact() const { return nullptr; }
};

/// Adds an effect to the registry, after those registered before it (the order candidates are
/// listed and reported in). Returns true, so a test fixture can register at static initialisation.
/// \throws std::invalid_argument on a null effect or a name already registered.
bool register_effect(std::shared_ptr<const Effect> effect);
/// The registered effect of that name (nullptr: none). The built-in effects are always registered.
const Effect* find_effect(const std::string& name);
/// Every registered effect, in registration order.
std::vector<const Effect*> registered_effects();
/// The names of the effects of one family, in registration order. The reference stays valid;
/// its contents grow when an effect is registered.
const std::vector<std::string>& effect_names(FamilyKind family);
/// The default number of grid offsets of repeated blocked CV for these candidates (Effect::cv_offsets).
int default_cv_offsets(const std::vector<std::string>& candidates);

}  // namespace hil::diagnose
