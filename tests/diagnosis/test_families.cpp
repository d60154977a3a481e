// The blind suite over motion families (issue 32, items 1 and 4): every effect the independent
// truth (hil::contact_truth) can hide alone, with drawn magnitudes, on three motion families,
// diagnosed without knowing the scenario.
//
// Rules written and committed (2026-12-01) before any of these draws ran:
//  * Effects: clean (no effect); sensor_bias, sensor_gain, time_offset, viscous_friction,
//    contact_damping (friction on the total normal force, the truth's Kelvin-Voigt law),
//    nonlinear_stiffness, geometric_offset (the rig declares the plate's height off).
//  * Draw i of effect e: seed 32,600,000 + 1000 e + i (i >= 1000: 36,600,000 + 10,000 e + i), never
//    used before. Its motion family is i % 3: two-tone sinusoidal normal motion on a circle (smooth
//    sums of sinusoids), moves with stops (piecewise-linear), moves with stops on trapezoidal speed
//    profiles (the ramp drawn in 10-50 % of each move). Speeds, stops, amplitudes, yaw, ramp, the effect's magnitudes and the
//    noise all come from the seed (draw() below: the order of the draws is part of the rule).
//  * Fine velocity resolution (2e-5 m/s): straight moves at the paper's 2e-4 m/s carry structure
//    of their own (test_unexplained's QuantisedTwist).
//  * CI draws 6 per effect (i = 0..5, two per family); HIL_FAMILY_DRAWS=N is the full draw, i = 100
//    .. 100 + N - 1 (50: docs/diagnosis.md).
//  * Second full draw (rule added 2026-12-02, before it ran): HIL_FAMILY_FIRST=200, i = 200..249,
//    never drawn before, the same rules. HIL_FAMILY_FIRST=F moves any full draw (OffTheSuite's too)
//    to i = F..F + N - 1; F = 133, N = 1 replays one draw of the first full draw.
//  * Third full draw of contact_damping (rule added 2026-12-03, before it ran, after the damping's
//    normal force was clipped at lift-off): HIL_FAMILY_FIRST=300, i = 300..349, never drawn
//    before, the same rules.
//  * Fourth full draw of contact_damping (rule added 2026-12-03, before it ran, after quantum_of
//    saw steps below the smallest gap and through zero): HIL_FAMILY_FIRST=400, i = 400..449, never
//    drawn before, the same rules.
//  * After the delay's lag form (a pure delay followed by a fitted first-order filter, the values
//    a form the run prefers; rule added 2026-12-03, before these ran): HIL_FAMILY_FIRST=500, i =
//    500..549, never drawn before, the same rules, for time_offset (the pure delay: that the form
//    breaks nothing), the averaging sensor chain and the first-order filter (OffTheSuite).
//  * After the lag form was made to widen only (rule added 2026-12-03, before these ran; the draw
//    above, i = 500..549, took the values of a form the run preferred, and failed):
//    HIL_FAMILY_FIRST=600, i = 600..649, never drawn before, the same rules, for the first-order
//    filter (OffTheSuite) and time_offset.
//  * After contact_damping's Hunt-Crossley form (rule added 2026-12-03, before these ran):
//    HIL_FAMILY_FIRST=700, i = 700..749, never drawn before, the same rules, for contact_damping
//    (that a linear dashpot's runs keep their intervals).
//  * After the Hunt-Crossley form gives the values where the run prefers it (rule added
//    2026-12-03, before these ran): HIL_FAMILY_FIRST=800, i = 800..849, never drawn before, the
//    same rules, for contact_damping.
//  * With the folds' spread information-weighted (CR2 with Satterthwaite's degrees of freedom;
//    rule committed in 395f5b2 before these ran, the engine change then reverted, kept on branch
//    experiment/cr2-folds-spread): HIL_FAMILY_FIRST=900, i = 900..949, for sensor_bias,
//    sensor_gain, viscous_friction, geometric_offset, contact_damping, time_offset and
//    nonlinear_stiffness. Drawn: i = 900..949 is used; a later draw takes other indices. Coverage
//    held for all; the failures were the earlier draws' and the stiffness exponent's widths (mean
//    z² 0.41), which the plain jackknife gives on the same draws too (docs/diagnosis.md).
//  * With contact_damping's friction bound (0 <= damping_friction <= μ D, commit 0baf016; the same
//    rules): HIL_FAMILY_FIRST=1000, i = 1000..1049 in the seeds' own range for i >= 1000, for
//    contact_damping (named 47: the bound refused two real dampings, a delay named instead) and
//    OffTheSuite's Hunt-Crossley damping. The bound was replaced (μ_D >= 0, and no friction without
//    a damping force; the same rules) and drawn on i = 1050..1099 (docs/diagnosis.md).
//  * With the plate's calibration tolerance on the reported std (92cf86c): i = 1000..1049 for
//    sensor_gain; with sensor_gain's two references (31722a4; the same rules): i = 1100..1149 for
//    sensor_gain (docs/diagnosis.md, "The plate's two groups of components").
//  * With the friction's lever forms' values taken where the run prefers them (rule added
//    2026-12-04, before these ran; the same rules): HIL_FAMILY_FIRST=1150, i = 1150..1199, never
//    drawn before, for sensor_bias, geometric_offset, time_offset and sensor_gain.
//  * The motion's centre drawn (rule added 2026-12-04, before these ran): from i = 1200 on, the
//    centre of the circle or the moves' square is drawn uniform in ±1 mm on x and y, after every
//    other draw of the index. Before, every moves draw stopped at the same points of the reported
//    positions' 2 µm grid, so each draw's stops carried the same quantisation error (measured on
//    plate_height, docs/diagnosis.md). HIL_FAMILY_FIRST=1200, i = 1200..1249, never drawn before,
//    the same rules, for geometric_offset. Drawn: plate_height still biased (+0.42, se 0.115; on
//    the two-tone draws, which never stop, too): the stops were not the cause (docs/diagnosis.md).
//  * With the reported values corrected for the reported positions' errors in the variables
//    (ContactFamily::errors_in_variables; rule added 2026-12-04, before these ran; the same rules):
//    HIL_FAMILY_FIRST=1250, i = 1250..1299, never drawn before, for geometric_offset (plate_height's
//    bias, which the correction is for), and sensor_bias, nonlinear_stiffness and contact_damping
//    (that it breaks nothing where the parameters are not the plate's geometry). Before the draw,
//    after the first ctest: the correction is taken only where the score is smooth at the errors'
//    scale (the bias over ± 2σ within 0.25 of the one over ± σ; kErrorsInVariablesMismatch, set
//    before any run): the guides of the ACU runs and the blind suite's viscous runs failed without it;
//    and an axis held at one reported value for more than a quarter of the run is not declared.
//    Drawn 2026-12-04: plate_height +0.087 (se 0.094), not biased (+0.25 on the same draws with the
//    correction off); every effect named and covered, widths fail as before (docs/diagnosis.md).
//  * With the sandwich where the folds are within its reach (branch
//    experiment/sandwich-fold-reach-2026-12-05; rule added 2026-12-05, before these ran; the same
//    rules): a fold-comparable value's std is the block-clustered sandwich's (G blocks of twice
//    Andrews' AR(1) bandwidth, 5 to 40, t-widened) when G >= 10 and every fold's estimate lies
//    within that std of its linear prediction from the full fit; else as before (the larger of the
//    asymptotic std and the folds' spread). HIL_FAMILY_FIRST=1300, i = 1300..1349, never drawn
//    before, for every effect. Widths (mean z² >= 0.5) and coverage are what it is for; the
//    damping's and viscous coefficient's biases (stated, explained) are expected to show.
//    Drawn 2026-12-05 and landed: sensor_bias, time_offset, contact_damping, nonlinear_stiffness and
//    geometric_offset meet every rule (widths included, for the first time); none and sensor_gain
//    fail on naming (trapezoidal `unexplained`), viscous_friction on its bias (-0.34, se 0.16)
//    (docs/diagnosis.md, "The sandwich where the folds are within its reach").
//  * The truth's friction below the declared sticking threshold (rule added 2026-12-05, before
//    these ran). The truth slides with Coulomb friction down to 1 µm/s (kSlipRegularisation) while
//    the rig declares sticking below 0.1 mm/s (kStickBelow), where hil's nominal model predicts no
//    friction: every draw whose feet slip below 0.1 mm/s carries that difference from the declared
//    model besides its effect (found 2026-12-02 on the trapezoidal draws, whose slip passes slowly
//    through zero; the clean and gain draws said `unexplained` there). hil's candidate for it,
//    slow_slip, was added 2026-12-05. From this rule on a draw's causes are its effect and, where
//    hil names it, slow_slip, in either order:
//     - named: the effect first, or second after slow_slip (clean: `none`, or slow_slip alone);
//     - single: no second cause but slow_slip;
//     - where slow_slip is named, its μ_s / μ (slow_slip_mu_ratio, truth 1: the truth's μ is one at
//       every speed above 1 µm/s) is one more parameter of the effect in the interval rules below.
//       Since 2026-12-05 (later, before i = 1450..1499 ran) its truth is the truth's own law's,
//       slow_friction_ratio_of (0.86-1.0 on the trapezoidal development draws: many foot-samples
//       slip at a few µm/s, where the truth's regularised friction is weaker than μ B); the rules
//       are unchanged. Drawn 2026-12-05: sensor_bias, sensor_gain and contact_damping pass; the
//       others fail on μ_s / μ's bias (+0.74 to +2.04 mean z: the reported twist's quantisation
//       reads the friction fully developed where it is not), geometric_offset on plate_tilt_x's
//       too (docs/diagnosis.md, "Friction below the declared sticking threshold").
//       Since 2026-12-06 (before i = 1500..1549 ran) its truth is that law's over the slips the
//       reported twist resolves (truth_of: from half its step, 10 µm/s, up; 0.995-1.000 on the
//       development draws), and its std holds the slip directions' error (slip_direction_error).
//    HIL_FAMILY_FIRST=1350, i = 1350..1399, never drawn before, every effect. Drawn 2026-12-05:
//    none named 49 of 50 (was 37), no second cause in any draw, every effect's own parameters
//    covered and unbiased (viscous +0.08, se 0.14); slow_slip's μ_s / μ fails its intervals (44 of
//    86 inside: values within a few per cent of 1, the sandwich's std 0.05-1 %), so none,
//    time_offset and viscous_friction fail on it, and sensor_gain on naming (43 of 50)
//    (docs/diagnosis.md, "Friction below the declared sticking threshold").
//  * With slow_slip's slip directions as an error in the variables (slip_direction_error) and
//    μ_s / μ's truth over the slips the reported twist resolves (rule added 2026-12-06, before
//    these ran; the same rules): HIL_FAMILY_FIRST=1500, i = 1500..1549, never drawn before, every
//    effect. i = 1350..1499 is development data. Checked first on i = 1450..1499 (2026-12-06):
//    μ_s / μ 65 of 65 inside, but too wide on the clean draws (mean z² 0.16: the sandwich at a
//    small ν and the folds' spread, not the new term) and biased +0.2 to +0.46 mean z (~0.5 %).
//    Drawn 2026-12-06 all the same: μ_s / μ 81 of 81 inside, too wide (z² 0.03-0.32); sensor_bias,
//    nonlinear_stiffness and geometric_offset pass; none fails on the widths, sensor_gain on naming
//    (44), time_offset on τ's bias (+0.50, se 0.135), viscous_friction on its coefficient's (-0.35),
//    and time_offset, viscous_friction and contact_damping (this alone) on μ_s / μ's +0.10 to +0.43
//    mean z under the too-wide intervals (docs/diagnosis.md, "Friction below the declared sticking
//    threshold").
//  * With a value carried by one event reported on the model's std (f8c9c82, 2026-12-06: sandwich ν
//    below 3 on a run of at least 10 blocks; only slow_slip's μ_s K and μ_s / μ fall under it):
//    checked on development draws i = 1450..1499 only, no fresh draw. μ_s / μ 90 of 102 inside,
//    mean z² 1.80 (0.16 before); the same four effects pass (sensor_bias, sensor_gain,
//    contact_damping, nonlinear_stiffness); none, time_offset and viscous_friction fail on its bias
//    (+0.5 to +1.1 mean z: the reported twist reads μ_s K about 1 % high, measured without noise),
//    geometric_offset on plate_tilt_x (docs/diagnosis.md, "Friction below the declared sticking
//    threshold").
//    Fresh draw under that rule (rule added 2026-12-06 05:40 UTC, before it ran; the same rules):
//    HIL_FAMILY_FIRST=1550, i = 1550..1599, never drawn before, for none (the widths it failed on
//    i = 1500..1549; μ_s / μ's bias is expected to show, as on the development draws). Drawn
//    2026-12-06: named 49 of 50, μ_s / μ 13 of 13 inside, mean z² 0.97, biased (+0.81, se 0.16).
//    time_offset's i = 1500..1549 re-run under that rule (development data, 2026-12-06 evening):
//    τ 45 of 50 inside, mean z +0.42 (se 0.17); on two trapezoidal draws with slow_slip named τ is
//    carried by the same stop (ν 1.15, 2.3) and model-based, one of them 4.7 std off (a fold check
//    for the rule tried, not landed: docs/diagnosis.md, "Friction below the declared sticking
//    threshold").
//  * With the folds' check on the one-event rule (one_event_agrees, kOneEventFoldZ: the model's std
//    only where every fold that lost a fifth of the value's information or more lies within 2.576
//    of the Hausman spread sqrt(s_i² - s²); rule added 2026-12-06 23:35 UTC, before these ran; the
//    same rules): HIL_FAMILY_FIRST=1600, i = 1600..1649, never drawn before, for time_offset (τ
//    under the rule), none (μ_s / μ's widths, which the check widens where stops disagree) and
//    viscous_friction. μ_s / μ's bias is expected to show, as before. Drawn 2026-12-06 on dea5da6:
//    all three pass (none 47 named, μ_s / μ 13 of 13, z² 0.56; time_offset 49, τ 47 of 49;
//    viscous_friction 50, its coefficient 48 of 50, mean z -0.23, se 0.14); τ misses by z +31.8
//    on draw 36,631,619, model-based, where the check passes and fz's residual still follows the
//    penetration rate (docs/diagnosis.md, "Friction below the declared sticking threshold").
//  * With the component groups' check on the one-event rule (ContactFamily::component_groups: fz,
//    mx, my and fx, fy, mz; each group's one-step reading from the full optimum within 2.576 of its
//    Hausman spread, else the value takes the other rules and its std reaches across that group's
//    95 % interval, Reported::std_components; rule added 2026-12-07 02:56 UTC, before these ran,
//    after the engine test and one development draw, 36,631,619, whose τ it moves from z +31.8 to
//    +1.07; the same rules): HIL_FAMILY_FIRST=1650, i = 1650..1699, never drawn before, every
//    effect. μ_s / μ's bias is expected to show, as before. Drawn 2026-12-07 02:55-03:34 UTC on
//    2a03195: none, sensor_gain, time_offset (τ 47 of 50, mean z -0.08), viscous_friction and
//    contact_damping pass; sensor_bias and nonlinear_stiffness fail on μ_s / μ's bias,
//    geometric_offset on its widths (158 of 159 inside). The groups' check fired on none of the 81
//    one-event values (docs/diagnosis.md, "Friction below the declared sticking threshold").
//  * With slow_slip's μ_s K corrected for the slip directions' error (slip_direction_error's
//    replicates: their mean coefficient is the factor the twist's error reads μ_s K by, and μ_s K
//    and μ_s / μ are divided by it; an axis the twist reports exactly zero through a whole stretch
//    of slow samples takes no error; Reported::errors_in_variables says the correction; rule added
//    2026-12-07 06:50 UTC, before these ran, after development draws i = 1650..1699 of every
//    effect, where μ_s / μ's mean z went from +0.33 pooled to near zero; the same rules):
//    HIL_FAMILY_FIRST=1700, i = 1700..1749, never drawn before, every effect. Drawn 2026-12-07
//    06:55-07:24 UTC on 573ced6: μ_s / μ 89 of 89 inside, pooled mean z +0.05 (se 0.08), z² 0.57;
//    none, sensor_gain, time_offset, nonlinear_stiffness and geometric_offset (157 of 163) pass;
//    sensor_bias fails on bias_mx (-0.33, se 0.10; +0.05 on the draw before), viscous_friction on
//    its coefficient's known bias (-0.31, se 0.13; trapezoidal -0.52), contact_damping on μ_s / μ
//    (-0.15, se 0.06, under intervals about four times too wide, z² 0.07) (docs/diagnosis.md,
//    "Friction below the declared sticking threshold"). sensor_bias alone redrawn on i = 1750..1799
//    (2026-12-07 10:45 UTC, 56d3961, the same rules): passes, bias_mx -0.02 (se 0.11).
//  * With viscous_friction's column weighted by the probability that its contact touches under the
//    reported positions' quantum (touching_probability; rule added 2026-12-07 13:50 UTC, before
//    these ran, after the development draws i = 1350..1499 were measured without noise: the
//    coefficient's trapezoidal bias is the positions' 2 µm quantum where the feet lift off, not the
//    twist's, docs/diagnosis.md; the same rules): HIL_FAMILY_FIRST=1750, i = 1750..1799, never
//    drawn before for these effects, for viscous_friction (its coefficient's bias, expected gone)
//    and none (that the weighted candidate is not named on clean runs). Drawn 2026-12-07
//    13:55-14:00 UTC on dcdaa07: both pass; c_v 50 of 50 inside, mean z -0.001 (se 0.127),
//    z² 0.79, trapezoidal -0.08 (se 0.19); none named 47 of 50 (3 `unexplained`).
//  * With slow_slip's column on the damped normal force where contact_damping is in the model
//    (μ_s K (δ_e + τ_D δ̇)₊; μ_s / μ's truth in that form, truth_of; rule added 2026-12-07 16:42 UTC,
//    before these ran, after the damping development draws i = 1650..1699 were measured: their
//    folds' spread of μ_s / μ was the damping's share of the slow contacts' friction, which the
//    elastic column lacked; the same rules): HIL_FAMILY_FIRST=1750, i = 1750..1799, never drawn
//    before for contact_damping, for contact_damping (μ_s / μ's widths and bias, which failed on
//    i = 1700..1749). Drawn 2026-12-07 16:45-16:48 UTC on d14059d: passes; μ_s / μ 15 of 15
//    inside, mean z +0.25 (se 0.28), z² 1.14; D 47 of 50, -0.16 (se 0.15), z² 1.09.
//  * With the model form that puts the slow contacts' friction on the elastic force only
//    (ContactFamily::kSlowFrictionElasticForm, decided by the run and taken where it prefers it;
//    μ_s / μ's truth in the form reported; rule added 2026-12-07 17:08 UTC, before these ran; the
//    same rules): HIL_FAMILY_FIRST=1800, i = 1800..1849, never drawn before for contact_damping,
//    for contact_damping (that the form leaves the suite's damping covered and not too wide), and
//    OffTheSuite.DampingWithFrictionOnTheElasticForceIsNamedAndCovered's first full draw,
//    i = 100..149. Drawn 2026-12-07 17:12-17:17 UTC on de6d2e1: contact_damping passes (D 48 of
//    50, -0.11, z² 1.10; μ_s / μ 11 of 11, +0.35 (se 0.25), z² 0.74); the elastic-friction draw
//    fails on D's bias (-0.32, se 0.135, negative on every motion family; μ_s / μ 7 of 8, +0.48,
//    z² 0.98; named 49): not the slow friction's form, cause not found (docs/diagnosis.md).
//  * With μ_D D >= 0 a bound of the fit (held at 0 and reported as having run to its bound; the
//    check that refused a negative μ_D D removed; rule added 2026-12-07 19:40 UTC, before these
//    ran, after the elastic-friction draws' four misses were read: each was that check refusing a
//    true μ_D D = 0; the same rules): OffTheSuite.DampingWithFrictionOnTheElasticForceIsNamedAndCovered
//    on HIL_FAMILY_FIRST=200, i = 200..249, never drawn before; contact_damping on
//    HIL_FAMILY_FIRST=1850, i = 1850..1899, never drawn before; and, since the candidate now
//    competes where the check refused it, none, sensor_bias, sensor_gain, time_offset,
//    viscous_friction, nonlinear_stiffness and geometric_offset on HIL_FAMILY_FIRST=1800,
//    i = 1800..1849, never drawn before for any of these. Drawn 2026-12-07 19:49-20:13 UTC on
//    0808f03: the elastic-friction draw (D 48 of 49, -0.18, z² 0.64), contact_damping (D 48 of
//    50, -0.19, z² 1.01), sensor_gain, viscous_friction, nonlinear_stiffness and geometric_offset
//    pass; none (μ_s / μ -0.39, se 0.19, z² 0.48), sensor_bias (bias_my +0.35, se 0.10) and
//    time_offset (+0.30, se 0.13) fail, on runs where contact_damping is never named: their
//    values are the code's before the bound (docs/diagnosis.md).
//  * With the friction's lever forms weighted by the run's likelihoods (ModelForm::weighted: the
//    values the model's and both lever forms' averaged with weights exp(-excess / 2); rule added
//    2026-12-07 23:55 UTC, before these ran, after time_offset's τ lean was traced on i = 1800..1849
//    without noise to moves runs that preferred the tip's lever by 3-4 variances, less than the
//    margin that took it, and read τ 60-260 µs high on the centroid's; the same rules): every
//    effect on HIL_FAMILY_FIRST=1900, i = 1900..1949, never drawn before for any. Expected:
//    τ's and the tilting moments' offsets' leans smaller; nothing else worse. Drawn 2026-12-07
//    23:53 to 2026-12-08 00:13 UTC on 63e3a6e: time_offset (τ -0.12, se 0.11), sensor_bias,
//    none, sensor_gain, contact_damping and nonlinear_stiffness pass; geometric_offset fails on
//    plate_height's bias (+0.30, se 0.115) and viscous_friction on μ_s / μ's (+0.97, se 0.42),
//    both read identically by the code before on the same draws (docs/diagnosis.md).
//  * With slow_slip's μ_s / μ truth holding the truth's viscous friction below the declared sticking
//    threshold (slow_friction_ratio_of: hil's viscous column acts on sliding contacts only, so the
//    slow slip's term carries c_v u there; rule added 2026-12-08 03:10 UTC (committed in b9657ee),
//    before these ran, after the viscous draws i = 1900..1949 were probed: c_v u / μ is 0.1-1.1 %
//    of the ratio there, a third of their μ_s / μ bias, whose rest, +0.58 mean z on those draws,
//    was not explained then; the same rules): HIL_FAMILY_FIRST=1950, i = 1950..1999, never drawn
//    before, for viscous_friction. Expected: μ_s / μ's bias smaller, and it may still fail on the
//    unexplained rest. i = 1900..1949 is not blind for this change. Drawn 2026-12-08 03:11-03:13
//    UTC on b9657ee: passes; c_v 46 of 50 inside, +0.02 (se 0.14); μ_s / μ 8 of 9, +0.01 (se
//    0.44). Probed after (i = 1900..1949): the rest reads +0.08 with an exact twist and +0.43 with
//    c_v = 0, the reported twist's quanta on those motions (docs/diagnosis.md).
//  * Per effect, of n draws, at most ceil(10 %) may fail each of:
//     - named: the effect named first (clean: `none`);
//     - single: no second cause.
//  * Intervals: in each draw where the effect is named first, every reported parameter of it with a
//    truth gives z = (value - truth) / std; inside when |z| <= 1.96. Of the m values of an effect,
//    the count inside must not be in the binomial(m, 0.95) lower tail below 0.001 (a coverage
//    that low is not a 95 % interval's). Full draw only, also:
//     - widths: the mean of z² at least 0.5 (the intervals at most about 1.4 times too wide), and
//       when m >= 100 at most 99 % inside (the issue's 85-99 % band's upper side);
//     - bias: for each parameter name, |mean z| within joint_z(p) standard errors of the mean
//       (sd(z) / sqrt(count)), p the number of parameter names of the effect (Bonferroni over
//       them, at 95 % jointly).
//
// The CI draws pass. The full draw (2026-12-02, docs/diagnosis.md "The blind suite over motion
// families") does not, and is not asserted in CI: clean and gain runs on trapezoidal moves say
// `unexplained` (6 and 8 of 17 named: the declared sticking threshold against slow slip), the
// intervals of bias, gain, viscous friction and plate height are too wide (mean z² 0.1-0.6: one
// pooled σ² over the six components), damping is low (40 of 50 inside); the delay, the stiffness
// exponent and the delay off the suite's sensor chain pass. Rerun after the delay's plateau starts
// (2026-12-02), the delay's first draw is 48/50 inside but biased (mean z +0.50, se 0.12: the
// friction's lever on the two-tone draws, docs/diagnosis.md); its second draw (i = 200..249) passes.
// After the damping's clip at lift-off and its twist-level interval (2026-12-03), the damping's
// third draw (i = 300..349) passes: 49 of 50 inside, mean z -0.19 (se 0.11), mean z² 0.60. After
// quantum_of's change its fourth (i = 400..449) passes: 49 of 50, mean z -0.17 (se 0.11), z² 0.67.
// The first-order filter's draw (i = 100..149) failed (37 of 50 inside, mean z -1.43); with the
// delay's lag form widening the interval (i = 600..649): 45 of 47 inside, z² 1.23, still biased
// (mean z -0.42, se 0.15: the moves read the filter's lag short, now inside their intervals).
// time_offset's own draw then (i = 600..649): 50 of 50 inside, z² 0.55, biased (mean z +0.31, se
// 0.10; two-tone +0.58: the friction's lever, as in the first draw).
// After contact_damping's Hunt-Crossley form the damping's draw i = 700..749 passes (47 of 49 inside,
// mean z +0.09, z² 0.76). Hunt-Crossley damping (OffTheSuite below): i = 100..149 before the form 46
// of 50 inside, biased (+0.49: two-tone runs whose feet lift off read D 2-5 % high); after it, i =
// 200..249 49 of 49 inside and the exponent drawn 49 of 49, both still biased (+0.25, +0.24: the form
// widens only) and too wide (z² 0.23, 0.21: the moves' folds spread 8-12 %). With the form's values
// taken where the run prefers it: q = 1 (i = 300..349) unbiased (-0.02) but too wide (z² 0.013: the
// form is the truth's law there); q drawn (i = 200..249) passes (49 of 50, +0.004, z² 0.64); the
// damping's draw i = 800..849 passes (48 of 48, -0.03, z² 0.53).
//
// Label `blind`: minutes under sanitizers.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <iomanip>
#include <iostream>
#include <map>
#include <numeric>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <hil/diagnose/contact_family.hpp>
#include <hil/test/eigen.hpp>

#include "blind_runs.hpp"

namespace hil::diagnose::test {
namespace {

enum class Effect { none, bias, gain, delay, viscous, damping, stiffness, geometric };

std::string effect_name(Effect e) {
  switch (e) {
    case Effect::none: return "none";
    case Effect::bias: return "sensor_bias";
    case Effect::gain: return "sensor_gain";
    case Effect::delay: return "time_offset";
    case Effect::viscous: return "viscous_friction";
    case Effect::damping: return "contact_damping";
    case Effect::stiffness: return "nonlinear_stiffness";
    case Effect::geometric: return "geometric_offset";
  }
  return "?";
}

struct Drawn {
  ct::Scenario scenario;
  TripodRigOptions rig;
  Resolution resolution = kFine;
  std::string family, label;
};

/// Draw i's motion family (i % 3) and its speeds, stops, ramp, amplitudes and yaw, from r.
Drawn draw_motion(Draws& r, unsigned i, unsigned seed) {
  Drawn d{clean_scenario(), {}, kFine, "", ""};
  auto& t = d.scenario.trajectory;
  const Motion* families[] = {&kTwoTone, &kMoves, &kTrapezoidal};
  const Motion& family = *families[i % 3];
  family.apply(d.scenario);
  d.family = family.name;
  if (i % 3 == 0) {
    t.angular_rate_rad_per_s *= r.uniform(0.7, 1.3);
  } else {
    t.angular_rate_rad_per_s = r.uniform(4e-3, 12e-3) / t.radius_m;
    t.dwell_s = r.uniform(0.3, 1.0);
  }
  if (i % 3 == 2) t.ramp_fraction = r.uniform(0.1, 0.5);
  t.depth_amplitude_m *= r.uniform(0.8, 1.2);
  t.depth_amplitude2_m *= r.uniform(0.5, 1.5);
  t.yaw_amplitude_rad = r.uniform(0.02, 0.04);
  d.scenario.sensor.seed = seed;
  d.label = "seed " + std::to_string(seed) + " " + family.name;
  return d;
}

Drawn draw(Effect e, unsigned i) {
  // i >= 1000 would reach the next effect's seeds under 1000 e + i: its own range there.
  const unsigned k = static_cast<unsigned>(e);
  const unsigned seed = i < 1000u ? 32'600'000u + 1000u * k + i : 36'600'000u + 10'000u * k + i;
  Draws r(seed);
  Drawn d = draw_motion(r, i, seed);
  ct::Scenario& sc = d.scenario;
  std::ostringstream o;
  o << std::setprecision(3) << d.label;
  switch (e) {
    case Effect::none: break;
    case Effect::bias:
      for (int c = 0; c < 6; ++c)
        sc.sensor.bias(c) = r.sign() * (c < 2 ? r.uniform(0.3, 1.0) : c == 2 ? r.uniform(0.5, 2.0) : r.uniform(0.01, 0.04));
      o << ", bias " << sc.sensor.bias.transpose();
      break;
    case Effect::gain:
      for (int c = 0; c < 6; ++c) sc.sensor.gain(c) = r.sign() * r.uniform(0.01, 0.05);
      o << ", gain " << sc.sensor.gain.transpose();
      break;
    case Effect::delay:
      sc.sensor.delay_s = r.uniform(0.005, 0.025);
      o << ", delay " << 1e3 * sc.sensor.delay_s << " ms";
      break;
    case Effect::viscous:
      sc.law.viscous_n_s_per_m = r.uniform(100.0, 300.0);
      o << ", viscous " << sc.law.viscous_n_s_per_m << " N s/m";
      break;
    case Effect::damping:
      sc.law.damping_n_s_per_m = r.uniform(2000.0, 6000.0);
      sc.law.friction_on_total_normal = true;
      o << ", damping " << sc.law.damping_n_s_per_m << " N s/m";
      break;
    case Effect::stiffness:
      sc.law.exponent = r.uniform(1.2, 1.6);
      o << ", exponent " << sc.law.exponent;
      break;
    case Effect::geometric:
      d.rig.declared_plate_height_m = r.sign() * r.uniform(1e-5, 3e-5);
      o << ", declared plate height " << 1e6 * d.rig.declared_plate_height_m << " um";
      break;
  }
  // From i = 1200 on, the motion's centre too, last (the draws before it keep their values), so that
  // no two draws share the reported positions' grid phase. Drawn for a lead on plate_height's bias
  // (the moves' stops on the same grid points in every draw) that did not hold: docs/diagnosis.md.
  if (i >= 1200u) {
    sc.trajectory.centre_x_m = r.uniform(-1e-3, 1e-3);
    sc.trajectory.centre_y_m = r.uniform(-1e-3, 1e-3);
    o << ", centre (" << 1e6 * sc.trajectory.centre_x_m << ", " << 1e6 * sc.trajectory.centre_y_m << ") um";
  }
  d.label = o.str();
  return d;
}

/// P(X <= k) for X ~ binomial(m, p).
double binomial_cdf(unsigned k, unsigned m, double p) {
  double sum = 0.0;
  for (unsigned j = 0; j <= std::min(k, m); ++j)
    sum += std::exp(std::lgamma(m + 1.0) - std::lgamma(j + 1.0) - std::lgamma(m - j + 1.0) + j * std::log(p) + (m - j) * std::log1p(-p));
  return std::min(1.0, sum);
}

TEST(FamilySuite, BinomialTailIsTheSumOfItsTerms) {
  EXPECT_NEAR(binomial_cdf(6, 6, 0.95), 1.0, 1e-12);
  EXPECT_NEAR(binomial_cdf(0, 6, 0.95), std::pow(0.05, 6), 1e-18);
  EXPECT_NEAR(binomial_cdf(4, 6, 0.95), 1.0 - std::pow(0.95, 6) - 6 * std::pow(0.95, 5) * 0.05, 1e-12);
  // 50 at 95 %: 41 inside is below the 0.001 tail (7.6e-4), 42 is not (3.2e-3; 42 / 50 = 84 %).
  EXPECT_NEAR(binomial_cdf(41, 50, 0.95), 7.5598e-4, 1e-8);
  EXPECT_NEAR(binomial_cdf(42, 50, 0.95), 3.18834e-3, 1e-8);
}

struct Parameter {
  std::vector<double> z;
};

/// Diagnoses draws 0..5 (CI) or F..F + N - 1 ($env = N: the full draw; F = $HIL_FAMILY_FIRST, 100
/// unless set) and checks the rule
/// written at the top of this file for the cause `want`.
void meet_the_rule(const std::string& want, const char* env, const std::function<Drawn(unsigned)>& draw_i) {
  const bool full = std::getenv(env) != nullptr;
  const char* from = std::getenv("HIL_FAMILY_FIRST");
  const unsigned n = full ? static_cast<unsigned>(std::stoul(std::getenv(env))) : 6u;
  const unsigned first = !full ? 0u : from ? static_cast<unsigned>(std::stoul(from)) : 100u;
  const unsigned allowed = (n + 9) / 10;  // ceil(10 %)
  unsigned named = 0, single = 0;
  std::map<std::string, Parameter> params;
  std::map<std::string, unsigned> named_by_family;
  for (unsigned i = first; i < first + n; ++i) {
    const Drawn x = draw_i(i);
    const Diagnosed run = diagnose_scenario(x.scenario, x.rig, x.resolution);
    const Diagnosis& d = run.d;
    // slow_slip is the truth's own friction below the declared sticking threshold (the rule of
    // 2026-12-05 above): with it named first, the effect must be the second cause (clean: none).
    const bool slow_first = d.cause == "slow_slip";
    const bool slow_named = slow_first || d.second_cause == "slow_slip";
    const bool is_named = d.cause == want || (slow_first && (want == "none" ? d.second_cause.empty() : d.second_cause == want));
    named += is_named ? 1 : 0;
    single += d.second_cause.empty() || d.second_cause == "slow_slip" || (slow_first && d.second_cause == want) ? 1 : 0;
    std::ostringstream zs;
    if (is_named && d.extended) {
      ++named_by_family[x.family];
      for (const auto& q : d.extended->full.reported) {
        const bool slow = slow_named && belongs_to(q.name, "slow_slip");
        if (!slow && (!q.extension || !belongs_to(q.name, want))) continue;
        const auto truth = truth_of(q.name, x.scenario, d.extended->full, x.resolution.velocity_m_per_s, d.extended->model_form_taken);
        if (!truth) continue;
        const double z = (q.value - *truth) / q.std;
        params[q.name].z.push_back(z);
        zs << " " << q.name << " z " << std::setprecision(3) << z;
      }
    }
    std::cout << "FAMILY " << want << " " << x.label << ": " << (is_named ? "named" : "NOT NAMED")
              << (zs.str().empty() ? "" : " |" + zs.str()) << " | " << run.line << "\n";
  }
  // The summary table: per parameter, its count, share inside, mean z, its standard error, mean z².
  unsigned m = 0, inside = 0;
  double z2 = 0.0;
  std::ostringstream table;
  table << std::setprecision(3);
  std::vector<std::string> biased;
  const double zb = joint_z(params.size());
  for (const auto& [name, p] : params) {
    double mean = 0.0, sq = 0.0;
    unsigned in = 0;
    for (const double z : p.z) {
      mean += z / static_cast<double>(p.z.size());
      sq += z * z;
      in += std::abs(z) <= 1.96 ? 1 : 0;
    }
    double var = 0.0;
    for (const double z : p.z) var += (z - mean) * (z - mean) / std::max<double>(1.0, static_cast<double>(p.z.size()) - 1.0);
    const double se = std::sqrt(var / static_cast<double>(p.z.size()));
    m += static_cast<unsigned>(p.z.size());
    inside += in;
    z2 += sq;
    const bool bias = p.z.size() >= 2 && std::abs(mean) > zb * se;
    if (bias) biased.push_back(name);
    table << "\n  " << name << ": " << in << " of " << p.z.size() << " inside, mean z " << mean << " (se " << se << ")"
          << (bias ? " BIASED" : "") << ", mean z2 " << sq / static_cast<double>(p.z.size());
  }
  std::cout << "SUMMARY " << want << ": named " << named << ", single " << single << " of " << n << " (at most " << allowed
            << " may fail each); by family:";
  for (const auto& [f, k] : named_by_family) std::cout << " " << f << " " << k;
  std::cout << "; intervals " << inside << " of " << m << " inside" << table.str() << "\n";

  EXPECT_GE(named + allowed, n) << want << " named first in " << named << " of " << n;
  EXPECT_GE(single + allowed, n) << "a second cause in " << n - single << " of " << n;
  if (m > 0) {
    EXPECT_GE(binomial_cdf(inside, m, 0.95), 1e-3) << inside << " of " << m << " intervals inside" << table.str();
  }
  if (!full || m == 0) return;
  EXPECT_GE(z2 / m, 0.5) << "intervals too wide: mean z² " << z2 / m << table.str();
  if (m >= 100) {
    EXPECT_LE(inside, 0.99 * m) << inside << " of " << m << " inside: intervals too wide" << table.str();
  }
  EXPECT_TRUE(biased.empty()) << "biased beyond " << zb << " standard errors:" << table.str();
}

class Families : public ::testing::TestWithParam<Effect> {};

TEST_P(Families, MeetTheirRule) {
  const Effect e = GetParam();
  meet_the_rule(effect_name(e), "HIL_FAMILY_DRAWS", [e](unsigned i) { return draw(e, i); });
}

// The one delay of the first full draw whose interval missed the truth (draw 133, moves: 19.31 ms
// found as exactly 2 samples, 20.0 ms ± 4.7 µs, z = 147; docs/diagnosis.md, "Delay plateaus").
// On moves the cost is a staircase in τ: the truth's plateau (19.0-19.4 ms) lay between two
// quarter-sample starts, and the start on a whole sample sat on the steps clipped placements put
// there. A fixed case now: the delay within its 95 % interval, and that interval no narrower than
// the plateau it lies on can tell (w / √12 with w at least 0.1 ms: the plateaus are ~0.3 ms here).
TEST(FamilySuite, ADelayOnMovesIsFoundOnItsPlateau) {
  const Drawn x = draw(Effect::delay, 133);
  const Diagnosed run = diagnose_scenario(x.scenario, x.rig, x.resolution);
  ASSERT_EQ(run.d.cause, "time_offset") << run.line;
  ASSERT_TRUE(run.d.extended);
  bool seen = false;
  for (const auto& q : run.d.extended->full.reported) {
    if (q.name != "time_offset_s") continue;
    seen = true;
    const double truth = *truth_of(q.name, x.scenario, run.d.extended->full, x.resolution.velocity_m_per_s);
    EXPECT_NEAR(truth, 0.01931, 5e-5);
    EXPECT_LE(std::abs(q.value - truth), 1.96 * q.std) << q.value << " +- " << q.std;
    EXPECT_GE(q.std, 0.1e-3 / std::sqrt(12.0)) << "narrower than a plateau";
  }
  EXPECT_TRUE(seen) << run.line;
  EXPECT_TRUE(run.d.second_cause.empty()) << run.d.second_cause;
}

// Friction below the declared sticking threshold (issue 32; docs/diagnosis.md, "Friction below the
// declared sticking threshold"). The full draw's clean draw 110 (trapezoidal) said `unexplained`, mz
// 23 noise variances beyond white: its yawing feet slip slowly through the stops, below the 0.1 mm/s
// the rig declares, where the truth's Coulomb friction acts and the nominal model's does not. Rule
// written before the candidate ran on it: declared at 0.1 mm/s, slow_slip is named alone, its
// μ_s / μ within 1.96 std of the truth's (1 then, taken as the truth's μ at every speed above
// 1 µm/s; its own law's since 2026-12-05, SlowSlipsTruthIsTheTruthsRegularisedFriction, over the
// slips the reported twist resolves since 2026-12-06, QuantisedSlipDirectionsWidenTheRatio) and no
// structure left;
// the same run declared at 1 µm/s, below every measured slip, is `none` (slow_slip has nothing to fit).
TEST(FamilySuite, AFootSlidingBelowTheDeclaredStickingThresholdIsNamedSlowSlip) {
  const Drawn x = draw(Effect::none, 110);
  ASSERT_EQ(x.family, "trapezoidal");
  const Diagnosed declared = diagnose_scenario(x.scenario, x.rig, x.resolution);
  ASSERT_EQ(declared.d.cause, "slow_slip") << declared.line;
  EXPECT_TRUE(declared.d.second_cause.empty()) << declared.line;
  EXPECT_FALSE(declared.d.extended_residuals.structured()) << declared.line;
  ASSERT_TRUE(declared.d.extended);
  bool seen = false;
  for (const auto& q : declared.d.extended->full.reported) {
    if (q.name != "slow_slip_mu_ratio") continue;
    seen = true;
    // The truth's ratio on its own law over the slips the reported twist resolves (truth_of; 1
    // until 2026-12-05, then over every slip below the threshold, 0.980 here, until 2026-12-06).
    const double truth = *truth_of(q.name, x.scenario, declared.d.extended->full, x.resolution.velocity_m_per_s);
    EXPECT_LE(std::abs(q.value - truth), 1.96 * q.std) << q.value << " +- " << q.std << " against " << truth;
    EXPECT_LT(q.std, 0.2) << "too wide to tell slow slip from sticking";
  }
  EXPECT_TRUE(seen) << declared.line;
  const Diagnosed low = diagnose_scenario(x.scenario, x.rig, x.resolution, 1e-6);
  EXPECT_EQ(low.d.cause, "none") << low.line;
  EXPECT_TRUE(low.d.second_cause.empty()) << low.line;
}

/// The reported `param` of the nominal model with `extension` alone, fitted once on every sample of
/// `samples` (no folds) with their poses and twist reported at `reported` (default exact): what the
/// candidate reads where neither noise nor the reported resolutions can move it. nullopt: not reported.
std::optional<Reported> fitted_line(const Drawn& x, const std::vector<ct::Sample>& samples, const std::set<std::string>& extensions,
                                    const std::string& param, const ReportedResolution& reported = {}) {
  const cid::Scene scene = tripod_scene(x.scenario.plate, x.scenario.tripod, x.rig);
  const auto data = make_contact_data(scene, kStickBelow_m_per_s, to_measurements(samples, reported));
  const ContactFamily m(data, extensions);
  std::vector<int> all(data.obs.size());
  std::iota(all.begin(), all.end(), 0);
  for (const auto& q : fit(m, data.obs, all).reported)
    if (q.name == param) return q;
  return std::nullopt;
}
std::optional<Reported> fitted_line(const Drawn& x, const std::vector<ct::Sample>& samples, const std::string& extension,
                                    const std::string& param, const ReportedResolution& reported = {}) {
  return fitted_line(x, samples, std::set<std::string>{extension}, param, reported);
}
std::optional<double> fitted_alone(const Drawn& x, const std::vector<ct::Sample>& samples, const std::string& extension,
                                   const std::string& param) {
  const auto q = fitted_line(x, samples, extension, param);
  return q ? std::optional<double>(q->value) : std::nullopt;
}

// slow_slip's truth on the truth's own law (issue 32; docs/diagnosis.md, "Friction below the
// declared sticking threshold"). Until 2026-12-05 the suite took μ_s / μ = 1, but the truth's
// friction is μ B u / sqrt(u² + ε²): at slip speeds of a few ε (1 µm/s) it is weaker, and on
// trapezoidal moves many foot-samples slip that slowly. slow_friction_ratio_of computes the ratio
// from the truth's law alone. Development draw 1376 (trapezoidal, clean) slips slowly enough to
// take it 14 % below 1. Checked against hil's own fit where nothing else can move it: no noise, the
// exact poses and twist, slow_slip alone. Rule (the values seen in the measurement that found it,
// 0.862 and 0.8621): the truth below 0.9, the fit within 0.01 of it; with ε at 1 nm/s the truth
// within 1e-3 of 1. Fails with the old truth (1) and with a truth that ignores the slip speed.
TEST(FamilySuite, SlowSlipsTruthIsTheTruthsRegularisedFriction) {
  Drawn x = draw(Effect::none, 1376);
  ASSERT_EQ(x.family, "trapezoidal");
  x.scenario.sensor.noise_std.setZero();
  x.scenario.sensor.resolution.setZero();
  const double truth = slow_friction_ratio_of(x.scenario, kStickBelow_m_per_s);
  EXPECT_LT(truth, 0.9);
  const auto ratio = fitted_alone(x, ct::simulate(x.scenario), "slow_slip", "slow_slip_mu_ratio");
  ASSERT_TRUE(ratio);
  EXPECT_NEAR(*ratio, truth, 0.01);
  x.scenario.law.slip_regularisation_m_per_s = 1e-9;
  EXPECT_NEAR(slow_friction_ratio_of(x.scenario, kStickBelow_m_per_s), 1.0, 1e-3);
}

// slow_slip's μ_s / μ under the reported twist's quantisation (issue 32; docs/diagnosis.md,
// "Friction below the declared sticking threshold", 2026-12-06). A slow foot slips at one or two
// twist steps (20 µm/s), so the measured slip direction is off by tens of degrees: the column is
// measured with error. On the trapezoidal clean development draws, fitted without noise, the
// quantised twist moved μ_s / μ by -9 % to +6 % from the friction of the slips it resolves (its
// truth now, truth_of: the friction the truth's law gives there is fully developed, 0.995-1.000),
// while the fit's std was 1-3 %. slip_direction_error holds it (its std by re-perturbing the
// measured twist). Rule written with the measurement: on the four draws it moved most (1361,
// 1367, 1382, 1394), without noise, the ratio within 1.96 std of that truth and at least 3 %
// from it on three of them (so that only a wider interval holds it). Fails without the term.
TEST(FamilySuite, QuantisedSlipDirectionsWidenTheRatio) {
  int far = 0;
  for (const unsigned i : {1361u, 1367u, 1382u, 1394u}) {
    Drawn x = draw(Effect::none, i);
    ASSERT_EQ(x.family, "trapezoidal");
    x.scenario.sensor.noise_std.setZero();
    x.scenario.sensor.resolution.setZero();
    const auto q = fitted_line(x, ct::simulate(x.scenario), "slow_slip", "slow_slip_mu_ratio",
                               {x.resolution.position_m, x.resolution.velocity_m_per_s});
    ASSERT_TRUE(q) << i;
    const double truth = *truth_of(q->name, x.scenario, Fit{}, x.resolution.velocity_m_per_s);
    EXPECT_GT(truth, 0.99) << i;
    EXPECT_LE(std::abs(q->value - truth), 1.96 * q->std) << i << ": " << q->value << " +- " << q->std << " against " << truth;
    far += std::abs(q->value - truth) > 0.03 ? 1 : 0;
  }
  EXPECT_GE(far, 3);
}

// slow_slip's μ_s K corrected for the slip directions' error (issue 32; docs/diagnosis.md,
// "Friction below the declared sticking threshold", 2026-12-07). On the fresh draw i = 1650..1699
// μ_s / μ read high on every effect but the gain's (mean z +0.15 to +0.79, pooled +0.28): the
// reported twist's error does not only spread the ratio, it moves it. slip_direction_error's
// replicates measure how far (their mean coefficient) and μ_s K is divided by it; an axis the twist
// reports exactly zero through a stretch of slow samples takes no error (the square's moves run
// along one axis: adding error there over-corrected, pooled -0.21). Without noise, on the 99 clean
// trapezoidal development draws i = 1352..1649 that slip slowly, the least-squares ratio's mean z
// against its truth (truth_of) is +0.36 (se 0.12) and the corrected one's -0.02 (se 0.12); median
// errors +0.70 % and +0.12 %. Rule written with that measurement: the corrected mean z within 2
// standard errors of zero, the least-squares one more than 2 above it (the bias the correction is
// for is there), and the corrected median error nearer zero. Fails without the correction.
TEST(FamilySuite, SlowSlipIsCorrectedForItsSlipDirectionsError) {
  std::vector<double> raw, corrected, z_raw, z_corrected;
  for (unsigned i = 1352; i < 1650; i += 3) {
    Drawn x = draw(Effect::none, i);
    ASSERT_EQ(x.family, "trapezoidal") << i;
    x.scenario.sensor.noise_std.setZero();
    x.scenario.sensor.resolution.setZero();
    std::optional<Reported> q;
    try {
      q = fitted_line(x, ct::simulate(x.scenario), "slow_slip", "slow_slip_mu_ratio",
                      {x.resolution.position_m, x.resolution.velocity_m_per_s});
    } catch (const std::runtime_error&) {
      continue;  // no foot slips below the threshold on this draw
    }
    ASSERT_TRUE(q) << i;
    const double truth = *truth_of(q->name, x.scenario, Fit{}, x.resolution.velocity_m_per_s);
    const double least_squares = q->value - q->errors_in_variables;
    raw.push_back(least_squares - truth);
    corrected.push_back(q->value - truth);
    z_raw.push_back(raw.back() / q->std);
    z_corrected.push_back(corrected.back() / q->std);
  }
  ASSERT_GE(raw.size(), 90u);
  auto median = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return 0.5 * (v[(v.size() - 1) / 2] + v[v.size() / 2]);
  };
  const auto [mr, ser] = hil::test::mean_and_se(z_raw);
  const auto [mc, sec] = hil::test::mean_and_se(z_corrected);
  EXPECT_LE(std::abs(mc), 2.0 * sec) << "corrected mean z " << mc << " (se " << sec << ")";
  EXPECT_GT(mr, 2.0 * ser) << "least-squares mean z " << mr << " (se " << ser << ")";
  EXPECT_LT(std::abs(median(corrected)), std::abs(median(raw))) << median(corrected) << " against " << median(raw);
}

// slow_slip's friction on the damped normal force (issue 32; docs/diagnosis.md, "contact_damping's
// μ_s / μ: the misfit was slow_slip's column"). The truth's friction bound is its total normal force
// K δ + D δ̇ at every slip speed; slow_slip's column was μ_s K δ_e, so with contact_damping in the
// model the damping's share of the slow contacts' friction had no column. On the damping
// development draws i = 1650..1699 its folds then spread μ_s / μ 10-40 times its asymptotic std,
// and the sandwich took it. With contact_damping the column is μ_s K (δ_e + τ_D δ̇)₊, and μ_s / μ's
// truth is the truth's friction's ratio to that column (slow_friction_ratio_of's total-normal
// form). Rule written before it ran: on the trapezoidal damping development draws that slip
// slowly (1652 1655 1658 1664 1667 1670 1673 1685 1694), without noise and with the exact poses and
// twist, slow_slip + contact_damping fitted once read μ_s / μ within 0.01 of that truth on each,
// and on at least three the elastic column's truth lies 0.02 or more from it (the forms differ
// there, so the old column would fail).
TEST(FamilySuite, SlowSlipsFrictionFollowsTheDampedNormalForce) {
  int apart = 0;
  for (const unsigned i : {1652u, 1655u, 1658u, 1664u, 1667u, 1670u, 1673u, 1685u, 1694u}) {
    Drawn x = draw(Effect::damping, i);
    ASSERT_EQ(x.family, "trapezoidal") << i;
    x.scenario.sensor.noise_std.setZero();
    x.scenario.sensor.resolution.setZero();
    const auto q = fitted_line(x, ct::simulate(x.scenario), std::set<std::string>{"slow_slip", "contact_damping"}, "slow_slip_mu_ratio");
    ASSERT_TRUE(q) << i;
    const double total = slow_friction_ratio_of(x.scenario, kStickBelow_m_per_s, 0.0, true);
    const double elastic = slow_friction_ratio_of(x.scenario, kStickBelow_m_per_s, 0.0, false);
    EXPECT_NEAR(q->value, total, 0.01) << i << ": the elastic column's truth " << elastic;
    apart += std::abs(elastic - total) >= 0.02 ? 1 : 0;
  }
  EXPECT_GE(apart, 3);
}

// The clip at lift-off (issue 32, item 1; docs/diagnosis.md): the truth's normal force per foot is
// max(0, K δ + D δ̇), so a foot withdrawing faster than δ / (D / K) pushes nothing and does not
// pull. CI draw 3 (two-tone, D = 5,543 N s/m) lifts off; with its noise, a damping column that
// pulled there gave 5,440 ± 28 (z -3.6). Rule written before the clipped candidate ran: without
// noise, with the exact poses and twist, the truth clips at least 10 foot-samples and D, fitted
// alone, is within 0.5 % of it.
TEST(FamilySuite, ADampingWhoseFeetLiftOffIsNotFittedLow) {
  Drawn x = draw(Effect::damping, 3);
  x.scenario.sensor.noise_std.setZero();
  const double D = x.scenario.law.damping_n_s_per_m;
  ASSERT_NEAR(D, 5543.0, 1.0);
  const auto samples = ct::simulate(x.scenario);
  int clipped = 0;
  for (const auto& s : samples) {
    std::vector<ct::FootContact> feet;
    ct::plate_wrench(x.scenario.plate, x.scenario.tripod, x.scenario.law, ct::true_state(x.scenario, s.t_s), &feet);
    for (const auto& foot : feet) clipped += foot.penetration_m > 0.0 && foot.normal_n == 0.0 ? 1 : 0;
  }
  EXPECT_GE(clipped, 10) << "the draw no longer lifts off";
  const auto fitted = fitted_alone(x, samples, "contact_damping", "damping_n_s_per_m");
  ASSERT_TRUE(fitted);
  EXPECT_NEAR(*fitted, D, 0.005 * D) << clipped << " foot-samples clipped";
}

/// Draw i of a sensor chain off the suite's: the motion from seed seed_base + i (draw_motion), then
/// `chain` draws the chain's settings from the same source, in its rule's order, and says them.
Drawn draw_chain(unsigned seed_base, unsigned i, const std::function<std::string(Draws&, Drawn&)>& chain) {
  const unsigned seed = seed_base + i;
  Draws r(seed);
  Drawn d = draw_motion(r, i, seed);
  const std::string said = chain(r, d);
  std::ostringstream o;
  o << std::setprecision(3) << d.label << said << " (time_offset_s truth "
    << 1e3 * *truth_of("time_offset_s", d.scenario, Fit{}, d.resolution.velocity_m_per_s) << " ms)";
  d.label = o.str();
  return d;
}

// Off the suite's sensor chain (issue 32, items 4 and 6). Rule written and committed before any of
// these draws ran (2026-12-01), the rule above with the cause time_offset, and:
//  * Draw i: seed 32,700,000 + i, never used before; motion as draw_motion (i % 3); then, in this
//    order, the wrench stream's delay τ uniform in 3-20 ms, the ADC averaging n instants (n uniform
//    in 2..20) over each period before t - τ (a trailing average: the sensor chains of the suites
//    above average nothing), the reported position's quantisation uniform in 1-5 µm and the twist's
//    in 1e-5-5e-5 m/s.
//  * The truth of time_offset_s is the chain's delay, τ + (n - 1) T / (2n) (truth_of): where a
//    trailing average is not a pure delay (at the kinks of moves), the interval must widen to hold
//    it; coverage is checked as above. HIL_OFF_SUITE_DRAWS=N: the full draw.
Drawn draw_off_suite(unsigned i) {
  return draw_chain(32'700'000u, i, [](Draws& r, Drawn& d) {
    auto& sensor = d.scenario.sensor;
    sensor.delay_s = r.uniform(0.003, 0.020);
    sensor.adc_subsamples = std::min(20, 2 + static_cast<int>(r.uniform(0.0, 19.0)));
    d.resolution = {"drawn", r.uniform(1e-5, 5e-5), r.uniform(1e-6, 5e-6)};
    std::ostringstream o;
    o << std::setprecision(3) << ", delay " << 1e3 * sensor.delay_s << " ms, ADC mean of " << sensor.adc_subsamples << ", quantisation "
      << 1e6 * d.resolution.position_m << " um, " << 1e3 * d.resolution.velocity_m_per_s << " mm/s";
    return o.str();
  });
}

TEST(OffTheSuite, AnAveragingSensorChainsDelayIsNamedAndCovered) { meet_the_rule("time_offset", "HIL_OFF_SUITE_DRAWS", draw_off_suite); }

// A filter's lag instead of a pure delay (issue 32, item 4's form mismatches). Rule written and
// committed (2026-12-03) before any of these draws ran: the rule above with the cause
// time_offset, and:
//  * Draw i: seed 32,800,000 + i, never used before; motion as draw_motion (i % 3); then, in this
//    order, the wrench stream's delay τ uniform in 0-10 ms and a first-order low-pass filter's time
//    constant τ_f uniform in 2-15 ms before the ADC (the suite's ADC averages nothing); the
//    suite's fine resolution.
//  * The truth of time_offset_s is the chain's low-frequency group delay, τ + τ_f (truth_of). The
//    filter is no delay at any single frequency (its group delay τ_f / (1 + (ω τ_f)²), its gain
//    1 / sqrt(1 + (ω τ_f)²): 2.3 % short at 2.3 Hz for 15 ms), so the interval must widen to hold
//    it; coverage is checked as above. HIL_FILTER_DRAWS=N: the full draw (i = 100..).
// The CI draws pass (3 of 6 inside). The full draw (2026-12-03, docs/diagnosis.md "A filter's lag
// instead of a pure delay") does not: 37 of 50 inside, mean z -1.43; on moves the delay is read
// about a fifth of τ_f short and the interval does not widen.
Drawn draw_filter(unsigned i) {
  return draw_chain(32'800'000u, i, [](Draws& r, Drawn& d) {
    auto& sensor = d.scenario.sensor;
    sensor.delay_s = r.uniform(0.0, 0.010);
    sensor.filter_time_constant_s = r.uniform(0.002, 0.015);
    std::ostringstream o;
    o << std::setprecision(3) << ", delay " << 1e3 * sensor.delay_s << " ms, first-order filter " << 1e3 * sensor.filter_time_constant_s
      << " ms";
    return o.str();
  });
}

TEST(OffTheSuite, AFirstOrderFiltersLagIsNamedAndCovered) { meet_the_rule("time_offset", "HIL_FILTER_DRAWS", draw_filter); }

// Hunt-Crossley damping instead of a linear dashpot (issue 32, item 4's form mismatches). Rule
// written and committed (2026-12-03) before any of these draws ran: the rule above with the cause
// contact_damping, and:
//  * Draw i: seed 32,900,000 + i, never used before; motion as draw_motion (i % 3); then D uniform
//    in 2,000-6,000 N s/m at the trajectory's mean depth (δ_ref = d0) and the dashpot
//    D (δ/δ_ref) δ̇: Hunt-Crossley's for the truth's linear spring (q = p = 1), no damping force
//    at first touch, the most at the deepest point; friction on the total normal force; the
//    suite's fine resolution.
//  * The truth of damping_n_s_per_m is the least-squares linear dashpot over the run's feet in
//    contact (truth_of, linear_damping_of); coverage is checked as above: where no linear dashpot
//    is the truth, the interval must widen to hold the best one. HIL_HUNT_CROSSLEY_DRAWS=N: the
//    full draw (i = 100..).
//  * After contact_damping's Hunt-Crossley form (rule added 2026-12-03, before these ran; the
//    draw i = 100..149 failed on bias, mean z +0.49): HIL_FAMILY_FIRST=200, i = 200..249, never
//    drawn before, the same rules.
//  * After that form gives the values where the run prefers it (rule added 2026-12-03, before
//    these ran; the draw i = 200..249 was covered but still biased, +0.25): HIL_FAMILY_FIRST=300,
//    i = 300..349, never drawn before, the same rules; for the rule below, HIL_FAMILY_FIRST=200,
//    i = 200..249.
// A second rule, written with the one above's second draw and before either ran: the dashpot's
// exponent drawn too, so that no form of the candidate is the truth's law.
//  * Draw i: seed 33,000,000 + i, never used before; as above, then, after D, q uniform in
//    0.5-1.5 (Hunt-Crossley's q is the contact's Hertz exponent: 1 for a flat punch, 1.5 for a
//    sphere; hil's form has q = 1). HIL_HUNT_CROSSLEY_Q_DRAWS=N: the full draw (i = 100..).
Drawn draw_hunt_crossley(unsigned i, bool draw_exponent = false) {
  const unsigned seed = (draw_exponent ? 33'000'000u : 32'900'000u) + i;
  Draws r(seed);
  Drawn d = draw_motion(r, i, seed);
  auto& law = d.scenario.law;
  law.damping_n_s_per_m = r.uniform(2000.0, 6000.0);
  law.delta_ref_m = d.scenario.trajectory.depth_m;
  law.damping_exponent = draw_exponent ? r.uniform(0.5, 1.5) : 1.0;
  law.friction_on_total_normal = true;
  std::ostringstream o;
  o << std::setprecision(4) << d.label << ", Hunt-Crossley damping " << law.damping_n_s_per_m << " N s/m at " << 1e6 * law.delta_ref_m
    << " um, q " << law.damping_exponent << " (damping_n_s_per_m truth " << linear_damping_of(d.scenario) << ")";
  d.label = o.str();
  return d;
}

// Why a linear dashpot reads a Hunt-Crossley contact high, and what the damping's Hunt-Crossley
// form does (docs/diagnosis.md, "Hunt-Crossley damping"). A development draw (i = 900, outside
// every rule's draws), two-tone, without noise, exact poses and twist, friction off: the feet lift
// off for part of each cycle, where the linear dashpot's force is clipped and Hunt-Crossley's
// vanishes. The linear fit reads D more than 1 % above the best linear dashpot; the form, whose δ̄
// is the rate-weighted mean interference, fits the truth to rounding and reads that dashpot.
// With the interference kept above zero (d1 = d0 / 2) the linear fit reads it within 0.5 %.
TEST(FamilySuite, ALinearDashpotReadsAHuntCrossleyContactHighOnlyWhereTheFeetLiftOff) {
  for (const bool lift_off : {true, false}) {
    Drawn x = draw_hunt_crossley(900);
    x.scenario.sensor.noise_std.setZero();
    x.scenario.sensor.resolution.setZero();
    x.scenario.law.mu = 0.0;
    if (!lift_off) x.scenario.trajectory.depth_amplitude_m = 0.5 * x.scenario.trajectory.depth_m;
    const double truth = linear_damping_of(x.scenario);
    const cid::Scene scene = tripod_scene(x.scenario.plate, x.scenario.tripod, x.rig);
    const auto data = make_contact_data(scene, kStickBelow_m_per_s, to_measurements(ct::simulate(x.scenario), {0.0, 0.0}));
    const ContactFamily m(data, {"contact_damping"});
    std::vector<int> all(data.obs.size());
    std::iota(all.begin(), all.end(), 0);
    auto forms = m.model_forms();
    ASSERT_EQ(forms.size(), 3u);  // the friction's two levers, Hunt-Crossley's dashpot
    auto* hc = dynamic_cast<const ContactFamily*>(forms.back().model.get());
    ASSERT_NE(hc, nullptr);
    ASSERT_GT(hc->damping_depth_m(), 0.0);
    EXPECT_TRUE(forms.back().decided_by_fit);
    EXPECT_TRUE(forms.back().taken_when_preferred);
    const Fit linear = fit(m, data.obs, all), form = fit(*forms.back().model, data.obs, all);
    auto D = [](const Fit& f) {
      for (const auto& q : f.reported)
        if (q.name == "damping_n_s_per_m") return q.value;
      return std::nan("");
    };
    if (lift_off) {
      EXPECT_GT(D(linear), 1.01 * truth);
      EXPECT_NEAR(D(form), truth, 1e-6 * truth);
      EXPECT_LT(form.rss, 1e-9 * linear.rss);
    } else {
      EXPECT_NEAR(D(linear), truth, 0.005 * truth);
    }
  }
}

TEST(OffTheSuite, HuntCrossleyDampingIsNamedAndCovered) {
  meet_the_rule("contact_damping", "HIL_HUNT_CROSSLEY_DRAWS", [](unsigned i) { return draw_hunt_crossley(i); });
}

TEST(OffTheSuite, HuntCrossleyDampingOfAnyExponentIsNamedAndCovered) {
  meet_the_rule("contact_damping", "HIL_HUNT_CROSSLEY_Q_DRAWS", [](unsigned i) { return draw_hunt_crossley(i, true); });
}

// Damping whose friction follows the elastic force only (issue 32; docs/diagnosis.md, "contact_damping's
// μ_s / μ: the misfit was slow_slip's column"). With contact_damping in the model slow_slip's
// friction follows the total normal force; the model form ContactFamily::kSlowFrictionElasticForm
// puts it on the elastic force, as a contact law with μ_D = 0 does. Measured on the damping
// development draws i = 1650..1699 with the truth's friction on either force (noise on, as
// drawn): the run rejects the wrong form by 18-3,800 long-run variances on 6 of 9 slow-slipping
// draws with the total law and prefers it by 310-1,530 on 5 of 9 with the elastic law; elsewhere
// the form widens μ_s / μ. Pinned here on two of them (development data, values seen): 1673 and
// 1685, the form rejected under the total law, taken under the elastic one, and μ_s / μ then
// within 1.96 std of its truth in that form.
TEST(FamilySuite, TheRunDecidesWhetherTheSlowFrictionFollowsTheDampingForce) {
  for (const unsigned i : {1673u, 1685u})
    for (const bool total : {true, false}) {
      Drawn x = draw(Effect::damping, i);
      ASSERT_EQ(x.family, "trapezoidal") << i;
      x.scenario.law.friction_on_total_normal = total;
      const Diagnosed run = diagnose_scenario(x.scenario, x.rig, x.resolution);
      ASSERT_TRUE(run.d.extended) << run.line;
      const Score& s = *run.d.extended;
      const bool taken = s.model_form_taken.rfind(ContactFamily::kSlowFrictionElasticForm, 0) == 0;
      bool rejected = false;
      for (const auto& r : s.model_forms_rejected) rejected = rejected || r.rfind(ContactFamily::kSlowFrictionElasticForm, 0) == 0;
      EXPECT_EQ(taken, !total) << i << " " << run.line;
      EXPECT_EQ(rejected, total) << i << " " << run.line;
      bool seen = false;
      for (const auto& q : s.full.reported) {
        if (q.name != "slow_slip_mu_ratio") continue;
        seen = true;
        const double truth = *truth_of(q.name, x.scenario, s.full, x.resolution.velocity_m_per_s, s.model_form_taken);
        EXPECT_LE(std::abs(q.value - truth), 1.96 * q.std)
            << i << (total ? " total" : " elastic") << ": " << q.value << " +- " << q.std << " against " << truth;
      }
      EXPECT_TRUE(seen) << i << " " << run.line;
    }
}

// The same blind (rule written and committed 2026-12-07, before any of these draws ran): the rule
// at the top of this file with the cause contact_damping, and:
//  * Draw i: seed 33,100,000 + i, never used before; motion as draw_motion (i % 3); then D uniform
//    in 2,000-6,000 N s/m, a linear dashpot, the friction on the elastic force only; the suite's
//    fine resolution.
//  * μ_s / μ, where slow_slip is named, against its truth in the form the diagnosis reports it in
//    (truth_of with the Score's model_form_taken). HIL_ELASTIC_FRICTION_DRAWS=N: the full draw
//    (i = 100.., HIL_FAMILY_FIRST moves it).
Drawn draw_elastic_friction_damping(unsigned i) {
  const unsigned seed = 33'100'000u + i;
  Draws r(seed);
  Drawn d = draw_motion(r, i, seed);
  d.scenario.law.damping_n_s_per_m = r.uniform(2000.0, 6000.0);
  d.scenario.law.friction_on_total_normal = false;
  std::ostringstream o;
  o << std::setprecision(4) << d.label << ", damping " << d.scenario.law.damping_n_s_per_m << " N s/m, friction on the elastic force";
  d.label = o.str();
  return d;
}

TEST(OffTheSuite, DampingWithFrictionOnTheElasticForceIsNamedAndCovered) {
  meet_the_rule("contact_damping", "HIL_ELASTIC_FRICTION_DRAWS", draw_elastic_friction_damping);
}

// μ_D D >= 0 held as a bound (issue 32; docs/diagnosis.md, "contact_damping's μ_s / μ: the misfit
// was slow_slip's column"). The elastic-friction draws' four misses, 141, 161, 163 and 194
// (development data: their values were read before this test), were each contact_damping refused
// by a check that μ_D D not lie two std below 0 (−18 ± 9 to −44 ± 15 N s/m), while the truth's is
// 0, on the bound: the check refused a true value at its one-sided rate. Rule written before the
// bound ran: with μ_D D a bound of the fit, each names contact_damping as the suite's rule does
// (first, or second after slow_slip) and no other cause, with
// damping_friction_n_s_per_m listed as having run to its bound or reported within 1.96 std of 0,
// and D within 1.96 std of its truth on at least three of the four.
TEST(FamilySuite, AFrictionOnTheElasticForceOnlyIsHeldAtItsBoundNotRefused) {
  int covered = 0;
  for (const unsigned i : {141u, 161u, 163u, 194u}) {
    const Drawn x = draw_elastic_friction_damping(i);
    const Diagnosed run = diagnose_scenario(x.scenario, x.rig, x.resolution);
    ASSERT_TRUE(run.d.extended) << i << " " << run.line;
    const Score& s = *run.d.extended;
    const auto& d = run.d;
    EXPECT_TRUE(d.cause == "contact_damping" ? d.second_cause.empty() || d.second_cause == "slow_slip"
                                             : d.cause == "slow_slip" && d.second_cause == "contact_damping")
        << i << " " << run.line;
    bool held = false;
    for (const auto& u : s.full.unidentifiable)
      held = held || (u.name == "damping_friction_n_s_per_m" && u.reason.find("bound") != std::string::npos);
    for (const auto& q : s.full.reported) {
      if (q.name == "damping_friction_n_s_per_m") {
        EXPECT_LE(std::abs(q.value), 1.96 * q.std) << i << ": " << q.value << " +- " << q.std;
        held = true;
      }
      if (q.name != "damping_n_s_per_m") continue;
      const double truth = *truth_of(q.name, x.scenario, s.full, x.resolution.velocity_m_per_s, s.model_form_taken);
      covered += std::abs(q.value - truth) <= 1.96 * q.std ? 1 : 0;
    }
    EXPECT_TRUE(held) << i << ": damping_friction_n_s_per_m neither held at its bound nor reported";
  }
  EXPECT_GE(covered, 3);
}

// The viscous coefficient's trapezoidal bias (issue 32, item 4; docs/diagnosis.md, "The viscous
// coefficient's trapezoidal bias"). The family draws read c_v low on trapezoidal moves (mean z
// -0.31 to -0.52). Measured without noise on the development draws i = 1350..1499, one change at a
// time, the suite's extended model (slow_slip and viscous_friction): the exact twist and exact
// positions read c_v +0.004 % (se 0.0004); positions at 2 µm -0.13 % (se 0.04); the same with the
// mean depth 40 µm deeper, no foot lifting off, +0.04 % (se 0.03); the quantised twist on top moves
// it -0.01 % (se 0.01). The viscous force does not vanish with the interference, and where a foot
// lifts off the positions' quantum decides its contact at random: the column now takes the
// probability that the foot touches (touching_probability).
// Rule, written before these draws ran: the trapezoidal viscous draws of i = 1900..2199 (100, never
// drawn before), without noise, the exact twist, fitted once on every sample (slow_slip and
// viscous_friction at the declared 0.1 mm/s; viscous_friction alone where no contact slips below
// it): with positions at 2 µm, |mean relative error| within 3 se; with the run's position quantum
// hidden from the family (the column read at the reported pose, as before), mean below zero by more
// than 2 se; with exact positions, |mean| under 0.02 %.
TEST(FamilySuite, TheViscousCoefficientIsNotReadLowWhereTheFeetLiftOffOnQuantisedPositions) {
  std::vector<double> weighted, hidden, exact;
  for (unsigned i = 1900; i < 2200; ++i) {
    if (i % 3 != 2) continue;
    Drawn x = draw(Effect::viscous, i);
    ASSERT_EQ(x.family, "trapezoidal");
    x.scenario.sensor.noise_std.setZero();
    x.scenario.sensor.resolution.setZero();
    const double truth = x.scenario.law.viscous_n_s_per_m;
    const auto samples = ct::simulate(x.scenario);
    const cid::Scene scene = tripod_scene(x.scenario.plate, x.scenario.tripod, x.rig);
    auto read = [&](const ContactData& d) {
      bool slow = false;
      for (const auto& cs : d.contacts)
        for (const auto& c : cs) slow = slow || (c.tangent.isZero() && c.slip_speed > 0.0 && c.slip_speed <= d.v_tm);
      const ContactFamily m(d, slow ? std::set<std::string>{"slow_slip", "viscous_friction"} : std::set<std::string>{"viscous_friction"});
      std::vector<int> all(d.obs.size());
      std::iota(all.begin(), all.end(), 0);
      for (const auto& q : fit(m, d.obs, all).reported)
        if (q.name == "viscous_n_s_per_m") return 100.0 * (q.value - truth) / truth;
      return std::nan("");
    };
    ContactData quantised = make_contact_data(scene, kStickBelow_m_per_s, to_measurements(samples, {2e-6, 0.0}));
    ASSERT_GT(quantised.position_quantum_m.minCoeff(), 0.0);
    weighted.push_back(read(quantised));
    quantised.position_quantum_m.setZero();
    hidden.push_back(read(quantised));
    exact.push_back(read(make_contact_data(scene, kStickBelow_m_per_s, to_measurements(samples, {0.0, 0.0}))));
  }
  ASSERT_EQ(weighted.size(), 100u);
  const auto [w, w_se] = hil::test::mean_and_se(weighted);
  const auto [h, h_se] = hil::test::mean_and_se(hidden);
  const auto [e, e_se] = hil::test::mean_and_se(exact);
  std::cout << "VISCOUS LIFT-OFF: weighted " << w << " % (se " << w_se << "), quantum hidden " << h << " % (se " << h_se
            << "), exact positions " << e << " % (se " << e_se << ")\n";
  EXPECT_LE(std::abs(w), 3.0 * w_se);
  EXPECT_LT(h, -2.0 * h_se);
  EXPECT_LT(std::abs(e), 0.02);
}

INSTANTIATE_TEST_SUITE_P(Issue32, Families,
                         ::testing::Values(Effect::none, Effect::bias, Effect::gain, Effect::delay, Effect::viscous, Effect::damping,
                                           Effect::stiffness, Effect::geometric),
                         [](const ::testing::TestParamInfo<Effect>& i) { return effect_name(i.param); });

}  // namespace
}  // namespace hil::diagnose::test
