//! Validation of a deserialised scenario against its keys' ranges (declared with the keys,
//! gathered in `bounds`) and the rules that relate keys (every problem at once, keyed by its
//! dotted path).

// The sibling files this one uses, named so that the import-cycle check sees them.
use super::design::{extent_across, DesignConfig, DesignOffset, MAX_DESIGN_PARCELS};
use super::line;
use super::mix::DistConfig;
use super::problems::Problem;
use super::schema::{BeltFrictionConfig, DriveConfig, DriveKind, ScenarioFile};
#[allow(unused_imports)]
use super::*;

/// A number for a message, brief: at most 6 significant digits, in the shortest form
/// (`0.65`, `1.23457`, `1e300`, `-2.5e-7`).
pub fn brief(v: f64) -> String {
    if !v.is_finite() {
        return v.to_string();
    }
    let rounded: f64 = format!("{v:.5e}").parse().unwrap_or(v);
    let plain = rounded.to_string();
    let sci = format!("{rounded:e}");
    if plain.len() <= sci.len() + 2 {
        plain
    } else {
        sci
    }
}

/// Range checks that collect a message per bad key.
pub(super) struct Checks<'a>(pub(super) &'a mut Vec<Problem>);

impl Checks<'_> {
    /// v is finite; else a problem (for keys whose range depends on other keys).
    pub(super) fn finite(&mut self, key: &str, v: f64) -> bool {
        if v.is_finite() {
            true
        } else {
            self.0.push(Problem::new(
                key,
                format!("{v} is not a finite number; allowed: a finite number"),
            ));
            false
        }
    }

    /// Every bound of `all_bounds` under the section `name` (and under none of `skip`),
    /// checked against the section's numbers at its key path.
    pub(super) fn ranges<T: Serialize>(&mut self, section: &T, name: &str, skip: &[&str]) {
        let value = match toml::Value::try_from(section) {
            Ok(v) => v,
            Err(e) => {
                self.0
                    .push(Problem::new(name, format!("cannot be checked: {e}")));
                return;
            }
        };
        for b in super::all_bounds() {
            let Some(path) = b.key.strip_prefix(name).and_then(|k| k.strip_prefix('.')) else {
                continue;
            };
            if skip.iter().any(|s| path.starts_with(s)) {
                continue;
            }
            for (key, v) in bounds::values_at(&value, path) {
                self.bound_at(&format!("{name}.{key}"), b, v);
            }
        }
    }

    /// v lies within `b` (reported at the bound's own key).
    fn bound(&mut self, b: &Bound, v: f64) {
        self.bound_at(b.key, b, v);
    }

    /// v lies within `b`, reported at `key` (the bound's key with its indices filled in).
    pub(super) fn bound_at(&mut self, key: &str, b: &Bound, v: f64) {
        if let Some(p) = b.problem(key, v) {
            self.0.push(p);
        }
    }

    /// A parcel's sides (length, width, height) and mass, with the keys `key("length")` …
    /// `key("mass")`, against `bounds` in that order.
    pub(super) fn box_size(
        &mut self,
        key: impl Fn(&str) -> String,
        bounds: &[Bound; 4],
        sides: [f64; 3],
        mass: f64,
    ) {
        let values = [sides[0], sides[1], sides[2], mass];
        for ((name, b), v) in ["length", "width", "height", "mass"]
            .into_iter()
            .zip(bounds)
            .zip(values)
        {
            self.bound_at(&key(name), b, v);
        }
    }
}

/// `run.cycle_starts`: at least one, finite, and each cycle over before the next starts.
fn validate_cycle_starts(starts: &[f64], cycle_time: f64, c: &mut Checks<'_>) {
    const KEY: &str = "run.cycle_starts";
    if starts.is_empty() {
        c.0.push(Problem::new(
            KEY,
            "is empty; allowed: one start time or more [s], e.g. [0] for the paper's one cycle",
        ));
        return;
    }
    // Each start's range is checked by key path (RunConfig::CYCLE_STARTS); their order
    // only once they all lie in it.
    if !starts.iter().all(|&s| RunConfig::CYCLE_STARTS.contains(s)) {
        return;
    }
    for (i, w) in starts.windows(2).enumerate() {
        if divertsim_core::sim::starts_in_cycle(w[0], w[1], cycle_time) {
            c.0.push(Problem::new(
                format!("{KEY}[{}]", i + 1),
                format!(
                    "{} s starts a cycle before the one at {} s has ended ({} s later, \
                     machine.cycle_time = {} s); allowed: at least {} s",
                    brief(w[1]),
                    brief(w[0]),
                    brief(w[1] - w[0]),
                    brief(cycle_time),
                    brief(w[0] + cycle_time)
                ),
            ));
        }
    }
}

/// The checks of `[machine]` (a line's further diverters get the same, keyed under theirs).
pub(super) fn validate_machine(f: &ScenarioFile, problems: &mut Vec<Problem>) {
    let mut c = Checks(problems);
    let m = &f.machine;
    c.ranges(m, "machine", &["drive.", "adaptive."]);
    if m.light_barrier.is_finite()
        && m.start_position.is_finite()
        && m.light_barrier > m.start_position
    {
        c.0.push(Problem::new(
            "machine.light_barrier",
            format!(
                "{} lies downstream of machine.start_position = {}; allowed: light_barrier ≤ start_position",
                m.light_barrier, m.start_position
            ),
        ));
    }
    if let Some(top) = m.arm_face_top {
        if top.is_finite() && m.arm_face_bottom.is_finite() && top <= m.arm_face_bottom {
            c.0.push(Problem::new(
                "machine.arm_face_top",
                format!(
                    "{} is not above machine.arm_face_bottom = {}; allowed: above {} m",
                    brief(top),
                    brief(m.arm_face_bottom),
                    brief(m.arm_face_bottom)
                ),
            ));
        }
    }
    validate_drive(&m.drive, &mut c);
    mix::validate_adaptive(&f.machine.adaptive, c.0);
}

/// The parcel against the arm's face band and its own height: the centre of mass inside
/// the box, and (without a mix, whose parcels the band is for) a parcel the arm can touch.
fn validate_heights(f: &ScenarioFile, c: &mut Checks<'_>) {
    let (m, p) = (&f.machine, &f.parcel);
    if let Some(hc) = p.com_height {
        if hc.is_finite() && p.height.is_finite() && hc > p.height {
            c.0.push(Problem::new(
                "parcel.com_height",
                format!(
                    "{} lies above the parcel's top (parcel.height = {}); allowed: (0, {}] m",
                    brief(hc),
                    brief(p.height),
                    brief(p.height)
                ),
            ));
        }
    }
    // The tallest parcel the band is for: the mix's (its default height is uniform 0.1–0.3
    // m; a records file's parcels are checked as they are drawn), else the scenario's.
    let tallest = if f.mix.is_default() {
        Some((
            p.height,
            "the parcel's top (parcel.height = ",
            "misses the parcel",
        ))
    } else if f.mix.records.is_none() {
        let h = f.mix.height.as_ref().map_or(0.3, DistConfig::largest);
        Some((
            h,
            "the tallest parcel of the mix (mix.height at most ",
            "misses every parcel",
        ))
    } else {
        None
    };
    if let Some((h, what, misses)) = tallest {
        if h.is_finite() && m.arm_face_bottom.is_finite() && h <= m.arm_face_bottom {
            c.0.push(Problem::new(
                "machine.arm_face_bottom",
                format!(
                    "{} m is at or above {what}{} m): the arm's face {misses}; allowed: below {} m",
                    brief(m.arm_face_bottom),
                    brief(h),
                    brief(h)
                ),
            ));
        }
    }
}

/// Every range and consistency check of the contract.
pub(super) fn validate(f: &ScenarioFile, problems: &mut Vec<Problem>) {
    if f.base.is_some() {
        problems.push(Problem::new(
            "base",
            "can only be given in a scenario file, not with --set",
        ));
    }
    validate_machine(f, problems);
    let mut c = Checks(problems);
    let m = &f.machine;
    let p = &f.parcel;
    c.ranges(p, "parcel", &[]);
    validate_heights(f, &mut c);
    if c.finite("parcel.offset", p.offset) {
        let sizes_ok = [p.length, p.width, p.angle_deg, m.belt_width]
            .iter()
            .all(|v| v.is_finite())
            && p.length > 0.0
            && p.width > 0.0
            && m.belt_width > 0.0;
        if sizes_ok {
            let (s, co) = p.angle_deg.to_radians().sin_cos();
            let across = p.length * s.abs() + p.width * co.abs();
            if across > m.belt_width {
                c.0.push(Problem::new(
                    "parcel.width",
                    format!(
                        "the parcel spans {across:.4} m across the belt at angle_deg = {}, wider than machine.belt_width = {}",
                        p.angle_deg, m.belt_width
                    ),
                ));
            } else if p.offset < 0.0 || p.offset + across > m.belt_width + 1e-12 {
                c.0.push(Problem::new(
                    "parcel.offset",
                    format!(
                        "{} puts the parcel off the belt; allowed: [0, {}] m (belt_width − the parcel's extent across the belt)",
                        p.offset,
                        at_most(m.belt_width - across + 1e-12)
                    ),
                ));
            }
        }
    }

    let mat = &f.materials;
    match &mat.belt_friction {
        BeltFrictionConfig::Constant(_) => {}
        BeltFrictionConfig::Table(points) => {
            if points.is_empty() {
                c.0.push(Problem::new(
                    "materials.belt_friction",
                    "the table is empty; give at least one [speed, μ] point",
                ));
            }
            for (i, [v, _]) in points.iter().enumerate() {
                let increasing = i == 0 || *v > points[i - 1][0];
                if !increasing {
                    c.0.push(Problem::new(
                        format!("materials.belt_friction[{i}][0]"),
                        format!(
                            "speeds must increase strictly; {v} follows {}",
                            points[i - 1][0]
                        ),
                    ));
                }
            }
        }
    }
    c.ranges(mat, "materials", &[]);
    c.ranges(&f.run, "run", &[]);
    validate_cycle_starts(&f.run.cycle_starts, m.cycle_time, &mut c);
    c.ranges(&f.limits, "limits", &[]);
    validate_design(&f.design, m.belt_width, &mut c);
    mix::validate(&f.mix, c.0);
    c.ranges(&f.camera, "camera", &[]);
    camera::validate(&f.camera, c.0);
    validate_line(f, c.0);
}

pub(super) fn validate_drive(d: &DriveConfig, c: &mut Checks<'_>) {
    if let Some(s) = d.max_swing_deg {
        c.bound(&DriveConfig::MAX_SWING_DEG, s);
    }
    let links = [
        (&DriveConfig::CRANK, d.crank),
        (&DriveConfig::COUPLER, d.coupler),
        (&DriveConfig::ROCKER, d.rocker),
        (&DriveConfig::GROUND, d.ground),
    ];
    for (b, v) in links {
        if let Some(v) = v {
            if d.kind != DriveKind::CrankRocker {
                c.0.push(Problem::new(
                    b.key,
                    "applies only to kind = \"crank-rocker\"",
                ));
            } else {
                c.bound(b, v);
            }
        }
    }
    let table = d.kind == DriveKind::Table;
    for (key, given) in [
        ("machine.drive.table", d.table.is_some()),
        ("machine.drive.points", d.points.is_some()),
    ] {
        if given && !table {
            c.0.push(Problem::new(key, "applies only to kind = \"table\""));
        }
    }
    if table {
        match (&d.table, &d.points) {
            (None, None) => c.0.push(Problem::new(
                "machine.drive.table",
                "kind = \"table\" needs table = \"FILE.csv\" (rows of t, alpha_deg) or points = [[t, alpha_deg], ...]",
            )),
            (Some(_), Some(_)) => c.0.push(Problem::new(
                "machine.drive.points",
                "cannot be given with machine.drive.table; give the rows in one of them",
            )),
            _ => {}
        }
        if d.max_swing_deg.is_some() {
            c.0.push(Problem::new(
                "machine.drive.max_swing_deg",
                "does not apply to kind = \"table\" (the table sets the swing)",
            ));
        }
    }
    if d.kind == DriveKind::CrankRocker {
        let given = [d.crank, d.ground].iter().filter(|v| v.is_some()).count();
        if given == 1 {
            c.0.push(Problem::new(
                if d.crank.is_some() { "machine.drive.ground" } else { "machine.drive.crank" },
                "give crank and ground together (with coupler and rocker), or neither to design the linkage from max_swing_deg",
            ));
        }
    }
}

/// The `[design]` checks (ranges, names, parcels on the belt), with key paths.
pub(super) fn validate_design(d: &DesignConfig, belt_width: f64, c: &mut Checks<'_>) {
    if d.parcels.is_empty() || d.parcels.len() > MAX_DESIGN_PARCELS {
        c.0.push(Problem::new(
            "design.parcels",
            format!(
                "{} parcels; allowed: 1 to {MAX_DESIGN_PARCELS}",
                d.parcels.len()
            ),
        ));
    }
    for (i, p) in d.parcels.iter().enumerate() {
        let k = |f: &str| format!("design.parcels[{i}].{f}");
        if p.name.trim().is_empty() {
            c.0.push(Problem::new(k("name"), "must not be empty"));
        } else if d.parcels[..i].iter().any(|q| q.name == p.name) {
            c.0.push(Problem::new(
                k("name"),
                format!("\"{}\" is used twice; names must be unique", p.name),
            ));
        }
        c.box_size(
            k,
            &super::design::DESIGN_BOX,
            [p.length, p.width, p.height],
            p.mass,
        );
        c.bound_at(&k("angle_deg"), &DesignParcelConfig::ANGLE_DEG, p.angle_deg);
        let sizes_ok = [p.length, p.width, p.angle_deg, belt_width]
            .iter()
            .all(|v| v.is_finite())
            && p.length > 0.0
            && p.width > 0.0
            && belt_width > 0.0;
        let offset_ok = match p.offset {
            DesignOffset::Value(v) => c.finite(&k("offset"), v),
            DesignOffset::Edge(_) => true,
        };
        if sizes_ok && offset_ok {
            let across = extent_across(p.length, p.width, p.angle_deg);
            let offset = p.offset_on(belt_width);
            if across > belt_width {
                c.0.push(Problem::new(
                    k("width"),
                    format!(
                        "the parcel spans {across:.4} m across the belt at angle_deg = {}, wider than machine.belt_width = {belt_width}",
                        p.angle_deg
                    ),
                ));
            } else if offset < 0.0 || offset + across > belt_width + 1e-12 {
                c.0.push(Problem::new(
                    k("offset"),
                    format!(
                        "{offset} puts the parcel off the belt; allowed: [0, {}] m (belt_width − the parcel's extent across the belt), \"near\" or \"far\"",
                        at_most(belt_width - across + 1e-12)
                    ),
                ));
            }
        }
    }
    let o = &d.overload;
    c.box_size(
        |f| format!("design.overload.{f}"),
        &super::design::OVERLOAD_BOX,
        [o.length, o.width, o.height],
        o.mass,
    );
    let search = d.search.pose_box();
    let problems = search.problems();
    for (key, message) in &problems {
        c.0.push(Problem::new(
            format!("design.search.{key}"),
            message.clone(),
        ));
    }
    if problems.is_empty() && belt_width.is_finite() {
        // The narrowest parcel of the class at its best angle must fit on the belt (the
        // extent a|sin φ| + b|cos φ| is smallest at an end of the band or at 0).
        let (a, b) = (search.length.0, search.width.0);
        let (lo, hi) = search.angle_deg;
        let narrowest = [lo, hi, 0.0f64.clamp(lo, hi)]
            .iter()
            .map(|&phi| extent_across(a, b, phi))
            .fold(f64::INFINITY, f64::min);
        if narrowest > belt_width {
            c.0.push(Problem::new(
                "design.search.width",
                format!(
                    "the narrowest parcel of the class ({a} × {b} m) spans {narrowest:.4} m across the belt at its best angle, wider than machine.belt_width = {belt_width}"
                ),
            ));
        }
    }
}

/// Most diverters a line may have after the first (a parcel's record names its diverter in
/// a byte).
pub const MAX_FURTHER_DIVERTERS: usize = 99;

/// The clear gaps a `line.gap` law may draw \[m]: from a slight overlap (raised to
/// `line.min_gap` at the induction) to a kilometre.
pub const GAP_SUPPORT: (f64, f64) = (-100.0, 1000.0);

/// The smallest and largest value `law` draws: its quantiles at the most extreme uniforms a
/// draw uses (the law's own support where it is bounded).
fn drawn_range(law: &divertsim_core::stats::distribution::Distribution) -> (f64, f64) {
    use divertsim_core::stats::distribution::open_unit;
    let (lo, hi) = (
        law.quantile(open_unit(0)),
        law.quantile(open_unit(u64::MAX)),
    );
    let (slo, shi) = law.support();
    (lo.max(slo).min(hi), hi.min(shi).max(lo))
}

/// Range and consistency checks of `[line]`; each further diverter's machine is checked as
/// the first's is, its problems keyed under `line.diverters[K].machine`.
pub(super) fn validate_line(f: &ScenarioFile, problems: &mut Vec<Problem>) {
    let l = &f.line;
    Checks(problems).ranges(l, "line", &[]);
    if let Some(g) = &l.gap {
        let law = g.distribution();
        let own = law.problems();
        let none = own.is_empty();
        for (param, message) in own {
            problems.push(Problem::new(format!("line.gap.{param}"), message));
        }
        // Every gap the law can draw, down to its most extreme uniform, stays a gap a belt
        // can hold: a law with an effectively infinite tail would give a rate of 0/h.
        let (lo, hi) = drawn_range(&law);
        if none && !(lo >= GAP_SUPPORT.0 && hi <= GAP_SUPPORT.1) {
            problems.push(Problem::new(
                "line.gap",
                format!(
                    "can draw gaps from {} to {} m; allowed: a law whose every draw lies within \
                     {} to {} m",
                    brief(lo),
                    brief(hi),
                    brief(GAP_SUPPORT.0),
                    brief(GAP_SUPPORT.1)
                ),
            ));
        }
    }
    if l.min_gap.is_none()
        && l.gap
            .as_ref()
            .is_some_and(|g| g.distribution().support().0 < 0.0)
    {
        problems.push(Problem::new(
            "line.min_gap",
            format!(
                "is needed: line.gap can go below 0 (down to {} m), and parcels cannot \
                 overlap at the induction; allowed: {}, e.g. 0.3",
                brief(l.gap.as_ref().map_or(0.0, |g| g.distribution().support().0)),
                LineConfig::MIN_GAP.allowed()
            ),
        ))
    }
    if l.arrivals.is_some() && (l.gap.is_some() || l.min_gap.is_some()) {
        problems.push(Problem::new(
            "line.arrivals",
            "cannot be given with line.gap or line.min_gap (the log gives the gaps); remove one",
        ));
    }
    if l.diverters.len() > MAX_FURTHER_DIVERTERS {
        problems.push(Problem::new(
            "line.diverters",
            format!(
                "{} diverters; allowed: at most {MAX_FURTHER_DIVERTERS} after the first",
                l.diverters.len()
            ),
        ));
        return;
    }
    let mut total = l.share;
    let mut reach_end = f.machine.arm_length;
    let mut previous = 0.0;
    for (i, d) in l.diverters.iter().enumerate() {
        let key = |name: &str| format!("line.diverters[{i}].{name}");
        total += d.share;
        for k in ["belt_speed", "belt_width"] {
            if d.machine.contains_key(k) {
                problems.push(Problem::new(
                    key(&format!("machine.{k}")),
                    format!("the belt is the line's: give machine.{k} once, in [machine]"),
                ));
            }
        }
        let machine = match line::diverter_file(f, i + 1) {
            Ok(file) => {
                let mut own = Vec::new();
                validate_machine(&file, &mut own);
                for mut p in own {
                    p.key = format!("line.diverters[{i}].{}", p.key);
                    problems.push(p);
                }
                Some(file.machine)
            }
            Err(p) => {
                problems.push(p);
                None
            }
        };
        // The working areas may not overlap: this diverter's light barrier (or pivot) lies
        // beyond the reach of the one before.
        let upstream = machine.as_ref().map_or(0.0, |m| {
            divertsim_core::analysis::line::inherit::working_area_start(
                m.light_barrier,
                m.start_position,
            )
        });
        if d.position.is_finite() && d.position + upstream < previous + reach_end {
            problems.push(Problem::new(
                key("position"),
                format!(
                    "{} m puts this diverter's working area (from {} m) inside the reach of \
                     the diverter before it (up to {} m); allowed: at least {} m",
                    brief(d.position),
                    brief(d.position + upstream),
                    brief(previous + reach_end),
                    brief(previous + reach_end - upstream)
                ),
            ));
        }
        previous = d.position;
        reach_end = machine.map_or(f.machine.arm_length, |m| m.arm_length);
    }
    if total > 1.0 + 1e-12 {
        problems.push(Problem::new(
            if l.diverters.is_empty() {
                "line.share".to_string()
            } else {
                format!("line.diverters[{}].share", l.diverters.len() - 1)
            },
            format!(
                "the shares sum to {} (line.share and every line.diverters[K].share); allowed: \
                 at most 1, the rest going straight through",
                brief(total)
            ),
        ));
    }
}

/// An upper bound for a message (the one the check uses, its tolerance included), to 6
/// decimals rounded down: a rejected value never looks
/// inside the range the message prints (0.4599996 shows as 0.459999, not 0.460000).
fn at_most(bound: f64) -> String {
    format!("{:.6}", (bound * 1e6).floor() / 1e6)
}

#[cfg(test)]
mod range_messages {
    /// Issue 27 (C14): the bound a message prints never contradicts the value it rejects.
    #[test]
    fn a_rejected_offset_never_looks_inside_the_printed_range() {
        assert_eq!(super::at_most(0.4599996), "0.459999");
        assert_eq!(super::at_most(0.46), "0.460000");
        let e = crate::config::load(
            None,
            &[
                "parcel.width=0.2400004".into(),
                "parcel.offset=0.4599998".into(),
            ],
        )
        .unwrap_err();
        let m =
            &e.0.iter()
                .find(|p| p.key == "parcel.offset")
                .unwrap()
                .message;
        assert!(m.contains("allowed: [0, 0.459999] m"), "{m}");
    }
}
