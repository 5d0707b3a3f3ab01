//! Regression tests of the issue "Contacts that hold, round two": one per fault of which
//! contact is active and when, each with its reproducer. Most are whole runs that must not
//! depend on the integrator's tolerance: at 1e-8 (the default) as at 1e-12 the same verdict,
//! the same stage sequence and the same strikes. The cases found by the tolerance audit
//! (`tolerance.rs`) are named after the wide random case they came from; switching their
//! fix off brings back the tolerance-dependent sequence noted with each.

use divertsim_core::model::active_set::{self, Body, ContactRow, Tolerances};
use divertsim_core::model::belt_friction::FrictionCoefficient;
use divertsim_core::model::drive::{DriveSpec, FourBar};
use divertsim_core::model::params::Scenario;
use divertsim_core::sim::{
    simulate, EventKind, NotDivertedReason, Obstacle, Outcome, SimResult, Stage,
};

/// A scenario of the audit: v, R_s, S_d, t_c, R_z, a, b, m, ΔP, φ [deg], μ_a, e*, μ_b.
struct Case {
    values: [f64; 13],
    drive: Drive,
}

/// The drive of a [`Case`]; swings in degrees, table rows (t [s], α [deg]).
enum Drive {
    CrankRocker(f64),
    Harmonic(f64),
    Cycloidal(f64),
    Poly345(f64),
    Table(&'static [[f64; 2]]),
}

impl Case {
    fn scenario(&self) -> Scenario {
        let [v, rs, sd, tc, rz, a, b, m, dp, phi, mu_a, e, mu_b] = self.values;
        let mut s = Scenario::paper_default();
        s.machine.belt_speed = v;
        s.machine.start_position = rs;
        s.machine.light_barrier = sd;
        s.machine.cycle_time = tc;
        s.machine.arm_length = rz;
        s.machine.drive = match self.drive {
            Drive::CrankRocker(sw) => {
                DriveSpec::CrankRocker(FourBar::centred(sw.to_radians(), 0.3, 0.15))
            }
            Drive::Harmonic(sw) => DriveSpec::Harmonic {
                max_swing: sw.to_radians(),
            },
            Drive::Cycloidal(sw) => DriveSpec::Cycloidal {
                max_swing: sw.to_radians(),
            },
            Drive::Poly345(sw) => DriveSpec::Poly345 {
                max_swing: sw.to_radians(),
            },
            Drive::Table(rows) => DriveSpec::Table {
                times: rows.iter().map(|r| r[0]).collect(),
                angles: rows.iter().map(|r| r[1].to_radians()).collect(),
            },
        };
        s.parcel.length = a;
        s.parcel.width = b;
        s.parcel.mass = m;
        s.parcel.offset = dp;
        s.parcel.angle = phi.to_radians();
        s.materials.arm_friction = mu_a;
        s.materials.restitution = e;
        s.materials.belt_friction = FrictionCoefficient::Constant(mu_b);
        s.run.duration = tc + 2.0;
        s
    }
}

fn at(s: &Scenario, tolerance: f64) -> SimResult {
    let mut s = s.clone();
    s.run.tolerance = tolerance;
    simulate(&s)
}

/// The run at 1e-8 and at 1e-12: the same verdict, stages and number of strikes, and no
/// failure. Returns the run at 1e-8.
fn tolerance_free(what: &str, s: &Scenario) -> SimResult {
    let (loose, tight) = (at(s, 1e-8), at(s, 1e-12));
    assert!(
        !matches!(loose.outcome, Outcome::Failed(_)),
        "{what}: {:?}",
        loose.outcome
    );
    assert_eq!(loose.outcome, tight.outcome, "{what}: verdicts");
    assert_eq!(loose.stages, tight.stages, "{what}: stages");
    assert_eq!(
        loose.impacts.len(),
        tight.impacts.len(),
        "{what}: strikes at {:?} against {:?}",
        loose.impacts.iter().map(|i| i.t).collect::<Vec<_>>(),
        tight.impacts.iter().map(|i| i.t).collect::<Vec<_>>()
    );
    loose
}

/// wide case 2197 of seed 2
const LEAVE: Case = Case {
    values: [
        1.6613465968152752,
        0.7580129139400786,
        0.0,
        1.4390311742308928,
        1.15,
        0.33458998293757886,
        0.13799754604840586,
        12.72946483665849,
        0.13751676770807872,
        10.462160438932955,
        0.034851744644246764,
        0.0903599497503075,
        0.6913068471131573,
    ],
    drive: Drive::Poly345(40.449657871148474),
};
/// wide case 19251 of seed 2
const REBOUND: Case = Case {
    values: [
        2.2226135398853715,
        0.21221203659935967,
        0.0,
        1.1309541047686178,
        0.9208443786836594,
        0.5648647909023088,
        0.35287602592537065,
        0.6847221885701689,
        0.00009281811426129105,
        -21.57999009339565,
        0.0,
        1.0,
        0.6133853721347653,
    ],
    drive: Drive::Cycloidal(37.82110937861057),
};
/// wide case 1950 of seed 2
const GRAZE: Case = Case {
    values: [
        1.706069365166671,
        0.800645911176993,
        0.0,
        1.2561462349734498,
        0.945463437991138,
        0.5715058006220147,
        0.21874869895871157,
        3.767668805920821,
        0.09530619721351263,
        -33.28381188185187,
        0.09355191760543259,
        0.25360436941296066,
        0.6940534913598873,
    ],
    drive: Drive::CrankRocker(36.06891976395278),
};
/// wide case 1234 of seed 1
const DRIFT: Case = Case {
    values: [
        0.9575823622733073,
        -0.014123341064077866,
        -0.014123341064077866,
        1.4673436556690027,
        1.0086367133295482,
        0.5381709081605572,
        0.12840053310866167,
        0.608624316048921,
        0.1086663737532989,
        23.04620392490351,
        0.0498936315553995,
        0.0,
        0.43592495562787437,
    ],
    drive: Drive::Table(&[
        [0.0, 0.0],
        [0.04455810794711652, 1.8049565975358914],
        [0.08911621589423303, 3.609913195071783],
        [0.13367432384134956, 5.414869792607674],
        [0.14879235132327623, 6.722282372855379],
        [0.1639103788052029, 10.445478399980333],
        [0.17902840628712957, 16.017635029708792],
        [0.19414643376905624, 22.590441926890236],
        [0.2092644612509829, 29.16324882407168],
        [0.2243824887329096, 34.735405453800134],
        [0.23950051621483626, 38.4586014809251],
        [0.25461854369676296, 39.766014061172804],
        [0.3025238721105368, 39.766014061172804],
        [0.35042920052431065, 39.766014061172804],
        [0.39833452893808446, 39.766014061172804],
        [0.44623985735185834, 39.766014061172804],
        [0.49414518576563216, 39.766014061172804],
        [0.542050514179406, 39.766014061172804],
        [0.5899558425931798, 39.766014061172804],
        [0.6378611710069537, 39.766014061172804],
        [0.6857664994207275, 39.766014061172804],
        [0.7336718278345014, 39.766014061172804],
        [0.7815771562482753, 39.766014061172804],
        [0.829482484662049, 39.766014061172804],
        [0.8773878130758229, 39.766014061172804],
        [0.9252931414895966, 39.766014061172804],
        [0.9731984699033706, 39.766014061172804],
        [1.0211037983171445, 39.766014061172804],
        [1.069009126730918, 39.766014061172804],
        [1.1169144551446921, 39.766014061172804],
        [1.1648197835584657, 39.766014061172804],
        [1.2127251119722398, 39.766014061172804],
        [1.2278431394541665, 38.4586014809251],
        [1.2429611669360932, 34.735405453800134],
        [1.2580791944180199, 29.16324882407168],
        [1.2731972218999466, 22.590441926890236],
        [1.2883152493818733, 16.017635029708792],
        [1.3034332768637997, 10.445478399980333],
        [1.3185513043457264, 6.722282372855379],
        [1.3336693318276531, 5.414869792607674],
        [1.3782274397747696, 3.609913195071783],
        [1.4227855477218863, 1.8049565975358914],
        [1.4673436556690027, 0.0],
    ]),
};
/// wide case 14935 of seed 5
const WIDEN: Case = Case {
    values: [
        2.056980406172834,
        0.8189214743180264,
        0.0,
        1.188051970981016,
        1.15,
        0.3474582412825169,
        0.21472452032332856,
        7.200538680932978,
        0.17094436855470352,
        -21.657727476631507,
        0.0,
        0.3921676840172616,
        0.21182863284482883,
    ],
    drive: Drive::Table(&[
        [0.0, 0.0],
        [0.04004197756698865, 1.0313827398067121],
        [0.0800839551339773, 2.0627654796134243],
        [0.12012593270096593, 3.0941482194201364],
        [0.1601679102679546, 4.1255309592268485],
        [0.20020988783494323, 5.15691369903356],
        [0.21492642194581657, 6.777751114353116],
        [0.22964295605668988, 11.319236631941358],
        [0.24435949016756323, 17.881873347375222],
        [0.25907602427843657, 25.16585057370558],
        [0.27379255838930994, 31.728487289139444],
        [0.28850909250018325, 36.26997280672769],
        [0.30322562661105656, 37.89081022204724],
        [0.35169235309096514, 37.89081022204724],
        [0.4001590795708737, 37.89081022204724],
        [0.4486258060507823, 37.89081022204724],
        [0.49709253253069086, 37.89081022204724],
        [0.5455592590105994, 37.89081022204724],
        [0.594025985490508, 37.89081022204724],
        [0.6424927119704166, 37.89081022204724],
        [0.6909594384503251, 37.89081022204724],
        [0.7394261649302337, 37.89081022204724],
        [0.7878928914101423, 37.89081022204724],
        [0.8363596178900509, 37.89081022204724],
        [0.8848263443699594, 37.89081022204724],
        [0.8995428784808328, 36.26997280672769],
        [0.9142594125917061, 31.728487289139444],
        [0.9289759467025794, 25.16585057370558],
        [0.9436924808134528, 17.881873347375222],
        [0.9584090149243261, 11.319236631941358],
        [0.9731255490351994, 6.777751114353116],
        [0.9878420831460728, 5.15691369903356],
        [1.0278840607130615, 4.1255309592268485],
        [1.0679260382800502, 3.0941482194201364],
        [1.1079680158470386, 2.0627654796134243],
        [1.1480099934140273, 1.0313827398067121],
        [1.188051970981016, 0.0],
    ]),
};
/// wide case 5779 of seed 3
const CLOSE: Case = Case {
    values: [
        1.1447844463798074,
        0.8491201636558705,
        0.0,
        1.3366983254115592,
        1.0,
        0.43522081750803154,
        0.38724039050895864,
        5.437118972964567,
        0.08939700769297193,
        -2.575451736599291,
        0.0,
        0.0946871364780419,
        0.3412132538221674,
    ],
    drive: Drive::Cycloidal(48.657263041533774),
};

/// Fault 1, the reproducer: the tip slides off a parcel edge at its corner, which
/// crosses the arm's line at the tip moving outward. It used to be struck on the arm face
/// with u_n = 2.81 m/s (S = 5.67 N·s, a false "diverted"); the corner passes beyond the
/// arm's end and the parcel escapes.
#[test]
fn a_corner_leaving_the_tip_is_not_struck_on_the_face() {
    let s = Case {
        values: [
            1.6649, 0.8566, 0.0, 1.1843, 1.15, 0.3733, 0.1241, 5.008, 0.2797, -31.874, 0.0, 0.1788,
            0.5638,
        ],
        drive: Drive::Harmonic(45.0),
    }
    .scenario();
    let r = tolerance_free("reproducer", &s);
    assert_eq!(
        r.outcome,
        Outcome::NotDiverted(NotDivertedReason::Escaped),
        "{:?}",
        r.stages
    );
    for i in &r.impacts {
        let at_tip = (f64::hypot(i.point[0], i.point[1]) - s.machine.arm_length).abs() < 1e-6;
        assert!(
            !(i.obstacle == Obstacle::ArmFace && at_tip),
            "struck on the face at the tip: {i:?}"
        );
    }
    assert!(r.overload.overload_ratio < 0.3, "{:?}", r.overload);
    // A poly-3-4-5 case of the audit: the tip leaves a corner it slid to; without the end
    // rule the corner was struck once more at 1e-8 ("tip F3 F2" against "tip F2").
    tolerance_free("wide case 2197 of seed 2", &LEAVE.scenario());
}

/// Fault 1, the tolerance-dependent example: a face strike at the tip end at 1e-8
/// (max_lateral 0.690 m), none at 1e-12 (0.644 m). Now none at either.
#[test]
fn a_corner_leaving_the_tip_does_not_depend_on_the_tolerance() {
    let s = Case {
        values: [
            2.3019, 0.858, 0.0, 1.4913, 1.0, 0.4249, 0.2618, 12.565, 0.0037, 2.537, 0.1981, 0.1702,
            0.3996,
        ],
        drive: Drive::CrankRocker(45.0),
    }
    .scenario();
    let r = tolerance_free("example", &s);
    let tight = at(&s, 1e-12);
    assert!(
        (r.max_lateral - tight.max_lateral).abs() < 1e-6 && (r.max_lateral - 0.644).abs() < 1e-3,
        "max_lateral {} at 1e-8, {} at 1e-12",
        r.max_lateral,
        tight.max_lateral
    );
}

/// Fault 2: as a flush side's leading corner passes the tip, the tip takes the flush edge;
/// its drift of 1e-8 to 9e-7 m/s was recorded as a plastic tip strike (an F3 stage of
/// S/S_fall ≈ 1e-9). The hand-off is one contact continuing: no strike, F5 then arm+tip.
#[test]
fn hand_off_drift_at_the_tip_is_not_a_strike() {
    let s = Case {
        values: [
            1.7825, 0.5822, 0.0, 1.1342, 1.0, 0.5199, 0.5001, 3.579, 0.0, 21.394, 0.0, 0.2102,
            0.3898,
        ],
        drive: Drive::CrankRocker(45.0),
    }
    .scenario();
    let r = tolerance_free("reproducer", &s);
    assert!(
        r.impacts.iter().all(|i| i.approach_speed > 1e-4),
        "a drift struck: {:?}",
        r.impacts
            .iter()
            .map(|i| i.approach_speed)
            .collect::<Vec<_>>()
    );
    let n = r.stages.len();
    assert_eq!(
        &r.stages[n - 2..],
        [Stage::F5, Stage::ArmTip],
        "{:?}",
        r.stages
    );
}

/// Fault 3: a table drive whose ramp (6° to 34° in 8 ms) put its peak rate between the 49
/// samples the guard culling trusted; a tip sweep was skipped (`off_near_side` at 1e-8,
/// `diverted` at 1e-12). The drive's bounds are now proved (see `drive.rs`).
#[test]
fn a_fast_table_ramp_is_not_culled() {
    let s = Case {
        values: [
            1.7119, 0.9732, 0.0, 1.36, 1.15, 0.3143, 0.1764, 2.0, 0.0527, 2.065, 0.1267, 0.5297,
            0.5434,
        ],
        drive: Drive::Table(&[
            [0.0, 0.0],
            [0.07572262903101218, 3.0],
            [0.15145, 6.0],
            [0.16148, 6.0],
            [0.16316, 6.8197],
            [0.16483, 11.5577],
            [0.1665, 20.214],
            [0.16817, 28.8703],
            [0.16985, 33.6083],
            [0.17152, 34.428],
            [0.18156, 34.428],
            [0.77023, 34.428],
            [0.81595, 34.428],
            [0.82357, 33.6083],
            [0.83119, 28.8703],
            [0.83881, 20.214],
            [0.84643, 11.5577],
            [0.85405, 6.8197],
            [0.86167, 6.0],
            [0.90739, 6.0],
            [1.13369, 3.0],
            [1.36, 0.0],
        ]),
    }
    .scenario();
    let r = tolerance_free("reproducer", &s);
    assert_eq!(r.outcome, Outcome::Diverted, "{:?}", r.stages);
}

/// A side pushed flush on the arm drifts off it (the acceleration-level constraints let the
/// gap's integration error grow, to 1e-7 m in 26 ms here): at the next event its far corner
/// was past the closed-contact tolerance, was dropped, and came back with a strike
/// ("F5 F4 F3 arm+tip" at 1e-8 against "F5 arm+tip"). The held contacts' drift is removed at
/// events.
#[test]
fn a_side_on_the_arm_keeps_its_far_corner_at_the_next_event() {
    let r = tolerance_free("wide case 1234 of seed 1", &DRIFT.scenario());
    assert_eq!(r.impacts.len(), 2, "{:?}", r.stages);
}

/// The tip slides along an edge 0.7° off the arm towards its corner; the tip contact's drift
/// (3.5e-8 m) placed the corner's crossing of the arm's line 3e-6 m inside the tip, where it
/// was struck on the face at 1e-8 but passed the tip at 1e-12. A corner at the end of an edge
/// the tip holds reaches the arm's line only at the tip (see `settle::end_tolerances`).
#[test]
fn a_corner_reaching_the_tip_along_a_held_edge_passes_it() {
    tolerance_free("wide case 14935 of seed 5", &WIDEN.scenario());
}

/// At an unrelated event (another corner's side flipping beyond the tip) a contact
/// separating at under 1 mm/s was taken into the active set and pulled back; at slightly
/// over 1 mm/s it was not, and returned with a strike. A pair in free flight is not taken up
/// at an event that has nothing to do with it.
#[test]
fn a_separating_pair_is_not_pulled_back_at_an_unrelated_event() {
    tolerance_free("wide case 5779 of seed 3", &CLOSE.scenario());
}

/// A fully elastic parcel (e* = 1, μ_a = 0) bounces 170 times on the arm at about 1 cm/s. A
/// struck pair's guard was re-armed half a nanometre deeper until a step began while it was
/// apart; at 1e-8 one step spans a bounce, so each next strike came 4.5e-8 s late, and the run
/// counted 169 bounces against 170. A rebounding pair's guard starts at its own root.
#[test]
fn a_rebound_is_watched_from_its_own_root() {
    let r = tolerance_free("wide case 19251 of seed 2", &REBOUND.scenario());
    assert_eq!(r.impacts.len(), 170);
}

/// The arm's tip passes a riding parcel's edge within 1e-8 m: at 1e-8 it touched it at
/// 2 µm/s and recorded a strike ("ride F3 ride"), at 1e-12 it missed. A touch that turns
/// within a negligible depth is a graze, as the end of a receding contact is.
#[test]
fn a_graze_is_not_a_strike() {
    tolerance_free("wide case 1950 of seed 2", &GRAZE.scenario());
}

/// A riding parcel that leaves the arm's reach while the arm still works has escaped, when it
/// leaves. The reach guard's event lies a hair inside the reach (a left root), where the
/// distance was tested again: the escape was noticed only at some later event (here at
/// 0.31 s instead of 0.025 s), or never, and the parcel was reported left on the belt.
#[test]
fn a_parcel_riding_out_of_reach_mid_cycle_has_escaped() {
    let mut s = Scenario::paper_default();
    s.parcel.length = 0.2;
    s.parcel.width = 0.1;
    s.parcel.mass = 0.5;
    s.parcel.offset = 0.6;
    s.machine.start_position = 0.95;
    let r = simulate(&s);
    assert_eq!(
        r.outcome,
        Outcome::NotDiverted(NotDivertedReason::Escaped),
        "{:?}",
        r.events
    );
    let escape = r
        .events
        .iter()
        .find(|e| e.kind == EventKind::Escape)
        .unwrap();
    assert!(escape.t < 0.1, "escaped at {} s", escape.t);
    assert!(r.impacts.is_empty());
}

/// A parcel wedged between two obstacles (the guide below, the arm's tip above) and struck
/// again within one instant: one at a time, plastic strikes lost the approach only by a
/// quarter per pair and 64 impulses did not settle it. Together, as one plastic impact with
/// Coulomb friction on the final slip, no contact approaches after it and energy is lost.
#[test]
fn a_wedged_parcel_settles_in_one_plastic_impact() {
    // 14.4 kg, 0.666 × 0.311 m; rows of the guide (corner 0) and the tip on edge 1 at the
    // instant the sequential strikes failed (u_n −12.5 and −3.9 m/s).
    let (m, inertia) = (14.426730170580095, 0.6497);
    let rows = [
        ContactRow {
            normal: [0.0, 1.0, 0.250557758660538],
            beta: 12.544277119520363,
            tangent: [1.0, -0.0, 0.2690672633406199],
            beta_t: -7.08239876333888,
            friction: 0.4813741806777279,
            slip: 7.08239876333888,
        },
        ContactRow {
            normal: [
                -0.37437989842482755,
                -0.927275413054512,
                -0.05249294222233257,
            ],
            beta: 3.8697730603181992,
            tangent: [-0.927275413054512, 0.37437989842482755, 0.15569566718352124],
            beta_t: 13.614658215543814,
            friction: 0.4813741806777279,
            slip: -13.614658215543814,
        },
    ];
    let body = Body {
        mass: m,
        inertia,
        external: [0.0; 3],
    };
    let tol = Tolerances {
        slip: 1e-8,
        force: 1e-12 * m,
        accel: 1e-10,
    };
    let sel = active_set::select_impact(&body, &rows, &tol).expect("a plastic impact");
    let dv = sel.solution.accel;
    let dot = |a: &[f64; 3]| a[0] * dv[0] + a[1] * dv[1] + a[2] * dv[2];
    let mut work = 0.0;
    for (i, r) in rows.iter().enumerate() {
        let (un, ut) = (-r.beta + dot(&r.normal), -r.beta_t + dot(&r.tangent));
        assert!(un >= -1e-9, "contact {i} still approaches at {un} m/s");
        let (pn, pt) = (
            sel.solution.normal_force[i],
            sel.solution.tangential_force[i],
        );
        assert!(pn >= 0.0 && pt.abs() <= r.friction * pn + 1e-9, "{pn} {pt}");
        work += pn * (-r.beta + 0.5 * dot(&r.normal)) + pt * (-r.beta_t + 0.5 * dot(&r.tangent));
        let _ = ut;
    }
    assert!(work < 0.0, "the impact created energy: {work} J");
}
