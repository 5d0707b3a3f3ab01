//! Validation of a deserialised scenario against the bounds table and the rules that relate
//! keys (every problem at once, keyed by its dotted path).

// The sibling files this one uses, named so that the import-cycle check sees them.
use super::design::{extent_across, DesignConfig, DesignOffset, MAX_DESIGN_PARCELS};
use super::problems::Problem;
use super::schema::{BeltFrictionConfig, DriveConfig, DriveKind, ScenarioFile};
#[allow(unused_imports)]
use super::*;

/// A number for a message: at most 6 significant digits, in the shortest form
/// (`0.65`, `1.23457`, `1e300`, `-2.5e-7`).
pub fn num(v: f64) -> String {
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

/// Every range and consistency check of the contract.
pub(super) fn validate(f: &ScenarioFile, problems: &mut Vec<Problem>) {
    if f.base.is_some() {
        problems.push(Problem::new(
            "base",
            "can only be given in a scenario file, not with --set",
        ));
    }
    let mut c = Checks(problems);
    let m = &f.machine;
    c.bound(&bounds::BELT_WIDTH, m.belt_width);
    c.bound(&bounds::BELT_SPEED, m.belt_speed);
    c.bound(&bounds::ARM_LENGTH, m.arm_length);
    c.bound(&bounds::CYCLE_TIME, m.cycle_time);
    c.bound(&bounds::START_POSITION, m.start_position);
    c.bound(&bounds::LIGHT_BARRIER, m.light_barrier);
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
    validate_drive(&m.drive, &mut c);

    let p = &f.parcel;
    c.box_size(
        |f| format!("parcel.{f}"),
        &bounds::PARCEL_BOX,
        [p.length, p.width, p.height],
        p.mass,
    );
    c.bound(&bounds::PARCEL_ANGLE, p.angle_deg);
    c.bound(&bounds::PARCEL_SPIN, p.spin);
    for (i, v) in p.velocity.iter().flatten().enumerate() {
        c.bound_at(
            &format!("parcel.velocity[{i}]"),
            &bounds::PARCEL_VELOCITY,
            *v,
        );
    }
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
                        "{} puts the parcel off the belt; allowed: [0, {:.6}] m (belt_width − the parcel's extent across the belt)",
                        p.offset,
                        m.belt_width - across
                    ),
                ));
            }
        }
    }

    let mat = &f.materials;
    match &mat.belt_friction {
        BeltFrictionConfig::Constant(mu) => c.bound(&bounds::BELT_FRICTION, *mu),
        BeltFrictionConfig::Table(points) => {
            if points.is_empty() {
                c.0.push(Problem::new(
                    "materials.belt_friction",
                    "the table is empty; give at least one [speed, μ] point",
                ));
            }
            for (i, [v, mu]) in points.iter().enumerate() {
                c.bound_at(
                    &format!("materials.belt_friction[{i}][0]"),
                    &bounds::BELT_FRICTION_SPEED,
                    *v,
                );
                c.bound_at(
                    &format!("materials.belt_friction[{i}][1]"),
                    &bounds::BELT_FRICTION_MU,
                    *mu,
                );
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
    c.bound(&bounds::ARM_FRICTION, mat.arm_friction);
    c.bound(&bounds::RESTITUTION, mat.restitution);

    if let Some(d) = f.run.duration {
        c.bound(&bounds::DURATION, d);
    }
    c.bound(&bounds::TOLERANCE, f.run.tolerance);
    c.bound(&bounds::DROP_HEIGHT, f.limits.drop_height);
    validate_design(&f.design, m.belt_width, &mut c);
    mix::validate(&f.mix, c.0);
    camera::validate(&f.camera, c.0);
    mix::validate_adaptive(&f.machine.adaptive, c.0);
}

pub(super) fn validate_drive(d: &DriveConfig, c: &mut Checks<'_>) {
    if let Some(s) = d.max_swing_deg {
        c.bound(&bounds::MAX_SWING, s);
    }
    let links = [
        (&bounds::CRANK, d.crank),
        (&bounds::COUPLER, d.coupler),
        (&bounds::ROCKER, d.rocker),
        (&bounds::GROUND, d.ground),
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
            &bounds::DESIGN_BOX,
            [p.length, p.width, p.height],
            p.mass,
        );
        c.bound_at(&k("angle_deg"), &bounds::DESIGN_ANGLE, p.angle_deg);
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
                        "{offset} puts the parcel off the belt; allowed: [0, {:.6}] m (belt_width − the parcel's extent across the belt), \"near\" or \"far\"",
                        belt_width - across
                    ),
                ));
            }
        }
    }
    let o = &d.overload;
    c.box_size(
        |f| format!("design.overload.{f}"),
        &bounds::OVERLOAD_BOX,
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
