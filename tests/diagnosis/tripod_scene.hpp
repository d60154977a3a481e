#pragma once
// The independent truth's tripod (hil::contact_truth, issue 12) as a hil contact_id rig, and its
// samples as the measurements `hil diagnose` reads: what a rig description and `hil acquire` would
// give for the same physical set-up, built only from what a rig would declare (geometry, frames)
// and what the rig reports (time, commanded pose and twist, plate wrench), never from the law.
#include <vector>

#include <hil/contact_id/identification.hpp>
#include <hil/contact_id/model.hpp>
#include <hil/contact_truth/tripod.hpp>

namespace hil::diagnose::test {

namespace cid = hil::contact_id;
namespace ct = hil::contact_truth;

/// The blind suite's base scenario (no effect): the tripod on a yawed and tilted plate presses in
/// and lifts off (depth 6e-5 ± 8e-5 m: out of contact about a quarter of the time), circles at
/// 5 mm/s and turns a little, so that every foot slides at 4-6 mm/s, well above the 1 mm/s sticking
/// threshold the rig declares (the truth's friction is regularised below 0.1 mm/s, hil's sticks).
/// Sensor: 100 Hz, one ADC instant per sample (averaging over the period would be a delay of
/// (n-1)/(2n) periods, time_offset by another name, in the clean run), 0.1 N / 0.005 N m noise and
/// resolution.
ct::Scenario pressing_and_sliding(double duration_s);

/// The sticking threshold the rig declares for pressing_and_sliding (m/s).
inline constexpr double kVtm_m_per_s = 1e-3;

/// What the rig declares about the tripod scene beyond the truth's plate and feet.
struct TripodRigOptions {
  /// Each foot: a downward tetrahedron, apex at the truth's foot tip, base this far above it (B z).
  double foot_height_m = 2e-3;
  double foot_base_radius_m = 1e-3;
  /// The plate: a box under the truth's plate surface (P z = 0), centred on o_P.
  double plate_half_size_m = 0.15;
  double plate_thickness_m = 0.02;
  /// The declared height of the plate's top face above o_P along P z (m): 0 where the truth puts it;
  /// another value is a rig whose declared geometry is off (geometric_offset's truth is then 0).
  double declared_plate_height_m = 0.0;
  /// Prior std of the declared uncertainties (plate height, tilts about P x and y through o_P).
  double height_prior_std_m = 5e-5;
  double tilt_prior_std_rad = 2e-3;
  /// The plate's declared calibration tolerance (force_plate.gain_tolerance of a rig file).
  double plate_gain_tolerance = 0.15;
};

/// Names of the declared uncertainties, in Scene::uncertainties order.
inline constexpr const char* kPlateHeight = "plate_height";
inline constexpr const char* kPlateTiltX = "plate_tilt_x";
inline constexpr const char* kPlateTiltY = "plate_tilt_y";

/// The hil scene of the truth's plate and tripod. Object 1 (on the end effector, T_attach = I) is
/// the tripod: the truth's robot moves the tripod's body frame B, and the rig reports B's pose as
/// the ee pose. Object 2 (fixed) is the plate, its body frame the truth's plate frame P, and the
/// force-plate frame is P too: the truth reports the wrench about o_P in P, so it needs no
/// conversion.
cid::Scene tripod_scene(const ct::Plate& plate, const ct::Tripod& tripod, const TripodRigOptions& o = {});

/// How the rig's reported pose and twist are quantised (0: not). The truth reports the commanded
/// state exactly; a real rig's encoders do not. Per world component, like cid::simulate: the ee
/// position and the linear velocity; orientation and angular velocity are left exact.
struct ReportedResolution {
  double position_m = 0.0;
  double velocity_m_per_s = 0.0;
};

/// The truth's samples as hil measurements: time, reported (commanded) pose and twist of B as the
/// ee's, measured plate wrench (P, about o_P: the scene's force-plate frame).
std::vector<cid::Measurement> to_measurements(const std::vector<ct::Sample>& samples, const ReportedResolution& r = {});

}  // namespace hil::diagnose::test
