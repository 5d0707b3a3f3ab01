//! Replicating the paper: rerun its analyses on the paper preset and judge its findings
//! (a)–(g) (docs/validation.md) from the numbers, never asserted. Gives every figure's data
//! as tidy CSV and the findings as JSON and Markdown; the CLI draws and writes them.
//!
//! The scenarios are the files of the configs directory (default `configs/paper`):
//! `machine.toml` (the preset), `fig05.toml` (capture), `fig06`–`fig08` (findings a–c, and
//! the trigger reference parcel), `fig03`, `fig13a/b`, `fig14a/b`, `fig15a/b` (paths).

use crate::analyses::{capacity, capture, overload, paths, poses, trigger};
use crate::config::{self, Loaded, Problem};
use crate::contract::{Analysis, Error, Hooks};
use divertsim_core::analysis::design::capacity::{linspace, CapacityMap, CapacityOptions};
use divertsim_core::analysis::design::worst_case::SearchSettings;
use divertsim_core::analysis::paper::trigger::{TriggerCurve, TriggerSettings};
use divertsim_core::run::sweep::Progress;
use divertsim_core::sim::Outcome;
use serde_json::{json, Value};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Whether a finding holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verdict {
    Holds,
    Partly,
    DoesNotHold,
}

impl Verdict {
    pub fn label(self) -> &'static str {
        match self {
            Verdict::Holds => "holds",
            Verdict::Partly => "holds in part",
            Verdict::DoesNotHold => "does not hold",
        }
    }
}

/// One finding of the paper and what divertsim found.
#[derive(Debug, Clone, PartialEq)]
pub struct Finding {
    pub id: &'static str,
    /// The paper's statement.
    pub paper: &'static str,
    /// divertsim's figure, in words and numbers.
    pub divertsim: String,
    /// The figure file that shows it.
    pub figure: &'static str,
    pub verdict: Verdict,
}

/// Everything replicate computed.
pub struct Replication {
    pub findings: Vec<Finding>,
    /// (file name, bytes) of the CSV and JSON outputs.
    pub files: Vec<(String, Vec<u8>)>,
    pub paths_figures: Vec<(String, Vec<paths::PathCase>)>,
    pub trigger: TriggerCurve,
    pub capture: capture::CaptureResult,
    pub overload: overload::OverloadReport,
    pub capacity: CapacityMap,
    /// The worst case the capacity map's cells hold against (the scenario's `[design]`).
    pub capacity_worst: divertsim_core::analysis::design::design_set::WorstDefinition,
    /// Wall time of the capacity map \[s].
    pub capacity_seconds: f64,
}

fn load(dir: &Path, name: &str) -> Result<Loaded, Vec<Problem>> {
    let p = dir.join(name);
    // The paper's analyses choose R_s themselves: the per-parcel trigger is refused.
    let loaded = config::load(Some(&p), &[]).and_then(super::fixed_trigger_only);
    loaded.map_err(|e| {
        e.0.into_iter()
            .map(|mut pr| {
                if !pr.key.starts_with(&p.display().to_string()) {
                    pr.key = format!("{}: {}", p.display(), pr.key);
                }
                pr
            })
            .collect()
    })
}

/// The scenario files replicate needs, loaded and validated (all problems at once).
#[derive(Debug)]
pub struct Inputs {
    pub machine: Loaded,
    pub cases: Vec<(String, Loaded)>,
}

const CASE_FILES: [&str; 11] = [
    "fig03.toml",
    "fig05.toml",
    "fig06.toml",
    "fig07.toml",
    "fig08.toml",
    "fig13a.toml",
    "fig13b.toml",
    "fig14a.toml",
    "fig14b.toml",
    "fig15a.toml",
    "fig15b.toml",
];

pub fn load_inputs(dir: &Path) -> Result<Inputs, Vec<Problem>> {
    let mut problems = Vec::new();
    let machine = load(dir, "machine.toml")
        .map_err(|p| problems.extend(p))
        .ok();
    let mut cases = Vec::new();
    for f in CASE_FILES {
        match load(dir, f) {
            Ok(l) => cases.push((f.trim_end_matches(".toml").to_string(), l)),
            Err(p) => problems.extend(p),
        }
    }
    match machine {
        Some(machine) if problems.is_empty() => Ok(Inputs { machine, cases }),
        _ => Err(problems),
    }
}

impl Inputs {
    fn case(&self, name: &str) -> &Loaded {
        &self
            .cases
            .iter()
            .find(|(n, _)| n == name)
            .expect("every case file is loaded")
            .1
    }
}

/// Run every analysis and judge the findings. The trigger curve and the capacity map (the
/// longest parts) keep their finished pieces in `memo` (a checkpoint).
pub fn compute(
    inputs: &Inputs,
    quick: bool,
    progress: Progress<'_>,
    memo: &dyn divertsim_core::run::memo::Memo,
) -> Result<Replication, Error> {
    let mut findings = Vec::new();
    let mut files = Vec::new();

    // Paths: findings (a)–(c) and the video figures.
    let groups: [(&str, &[&str]); 5] = [
        ("findings_abc", &["fig06", "fig07", "fig08"]),
        ("fig03", &["fig03"]),
        ("fig13", &["fig13a", "fig13b"]),
        ("fig14", &["fig14a", "fig14b"]),
        ("fig15", &["fig15a", "fig15b"]),
    ];
    let mut paths_figures = Vec::new();
    for (figure, names) in groups {
        let input: Vec<(PathBuf, String, _)> = names
            .iter()
            .map(|n| {
                (
                    PathBuf::from(format!("{n}.toml")),
                    n.to_string(),
                    inputs.case(n).scenario.clone(),
                )
            })
            .collect();
        let cases = paths::compute(input, progress);
        files.push((
            format!("{figure}.csv"),
            paths::csv(&cases).map_err(Error::io)?,
        ));
        paths_figures.push((figure.to_string(), cases));
    }
    let abc = &paths_figures[0].1;
    let (a, b, c) = (&abc[0].result, &abc[1].result, &abc[2].result);
    let judge = |ok: bool| {
        if ok {
            Verdict::Holds
        } else {
            Verdict::DoesNotHold
        }
    };
    findings.push(Finding {
        id: "a",
        paper: "The 0.7×0.1 m parcel at ΔP = 0, v = 0.65 m/s, t_c = 1.36 s, R_s = 0.8 m is not diverted.",
        divertsim: format!(
            "{}; largest y of the centre {:.3} m < P_max 0.7 m",
            a.outcome.verdict(),
            a.max_lateral
        ),
        figure: "findings_abc.svg",
        verdict: judge(a.outcome != Outcome::Diverted),
    });
    findings.push(Finding {
        id: "b",
        paper: "The same parcel at ΔP = 0.45 m, parallel to the belt, same setting, is diverted.",
        divertsim: b.outcome.verdict(),
        figure: "findings_abc.svg",
        verdict: judge(b.outcome == Outcome::Diverted),
    });
    findings.push(Finding {
        id: "c",
        paper: "The same parcel at ΔP = 0 with v = 2 m/s, t_c = 1.36 s, R_s = 0 is diverted.",
        divertsim: c.outcome.verdict(),
        figure: "findings_abc.svg",
        verdict: judge(c.outcome == Outcome::Diverted),
    });

    // (d) Trigger position R_s(v) for the reference displacement, Fig. 6's parcel.
    let speeds: Vec<f64> = if quick {
        vec![0.65, 1.3, 2.0]
    } else {
        (0..=33).map(|i| 0.65 + 0.05 * i as f64).collect()
    };
    let tsettings = TriggerSettings::default();
    let hooks = Hooks {
        progress,
        memo,
        ..Hooks::none()
    };
    let tcurve = trigger::TriggerCalibration::run(
        inputs.case("fig06"),
        &trigger::TriggerInputs {
            speeds: speeds.clone(),
            settings: tsettings.clone(),
        },
        &hooks,
    )
    .map_err(|e| Error::failed(format!("trigger: {e}")))?;
    files.push((
        "trigger.csv".into(),
        trigger::csv(&tcurve).map_err(Error::io)?,
    ));
    let roots: Vec<(f64, f64)> = tcurve
        .points
        .iter()
        .filter_map(|p| p.root().map(|r| (p.speed, r.start)))
        .collect();
    let falls = roots.len() >= 2 && roots.windows(2).all(|w| w[1].1 <= w[0].1 + 1e-3);
    let at2 = roots
        .iter()
        .min_by(|x, y| (x.0 - 2.0).abs().total_cmp(&(y.0 - 2.0).abs()))
        .copied();
    let zero_crossing = roots
        .windows(2)
        .find(|w| w[0].1 > 0.0 && w[1].1 <= 0.0)
        .map(|w| {
            // Linear interpolation of the speed where R_s = 0.
            w[0].0 + (w[1].0 - w[0].0) * w[0].1 / (w[0].1 - w[1].1)
        });
    let near_zero_at_2 = at2.is_some_and(|(_, r)| r.abs() <= 0.1);
    findings.push(Finding {
        id: "d",
        paper: "The R_s needed for the reference transverse displacement falls as v rises, to about 0 at v = 2 m/s.",
        divertsim: format!(
            "reference displacement {:.3} m; R_s {} from {} m at {} m/s to {} m at {} m/s ({} of {} speeds have a root); R_s = 0 at v ≈ {}",
            tcurve.reference.max_lateral,
            if falls { "falls monotonically" } else { "does not fall monotonically" },
            roots.first().map_or("-".into(), |r| format!("{:.3}", r.1)),
            roots.first().map_or("-".into(), |r| format!("{:.2}", r.0)),
            at2.map_or("-".into(), |r| format!("{:.3}", r.1)),
            at2.map_or("-".into(), |r| format!("{:.2}", r.0)),
            roots.len(),
            tcurve.points.len(),
            zero_crossing.map_or("(no crossing)".into(), |v| format!("{v:.2} m/s")),
        ),
        figure: "trigger.svg",
        verdict: match (falls, near_zero_at_2) {
            (true, true) => Verdict::Holds,
            (true, false) | (false, true) => Verdict::Partly,
            (false, false) => Verdict::DoesNotHold,
        },
    });

    // (e) Capture of the smallest parcel at the far edge, R_s from the trigger calibration.
    let cspeeds: Vec<f64> = if quick {
        vec![0.65, 2.0]
    } else {
        vec![0.65, 1.0, 1.5, 2.0, 2.3]
    };
    let cap = capture::Capture::run(
        inputs.case("fig05"),
        &capture::CaptureInputs {
            speeds: cspeeds.clone(),
            trigger: Some(tsettings),
            window: (-1.5, 1.0),
            window_step: if quick { 0.1 } else { 0.02 },
        },
        &hooks,
    )?;
    files.push(("capture.csv".into(), capture::csv(&cap).map_err(Error::io)?));
    // The paper's measure (Fig. 5): the corner is caught when the arm's path crosses the
    // corner's above the reach angle α_z; the margin α* − α_z says by how much.
    let rows: Vec<(f64, bool, Option<f64>, bool)> = cap
        .rows
        .iter()
        .filter_map(|r| {
            r.case.as_ref().map(|c| {
                let k = &c.kinematic;
                let margin = match (&k.crossing, k.reach_angle) {
                    (Some(x), Some(z)) => Some((x.alpha - z).to_degrees()),
                    _ => None,
                };
                (
                    r.speed,
                    k.captured,
                    margin,
                    c.sim.outcome == Outcome::Diverted,
                )
            })
        })
        .collect();
    let captured_rises = rows.len() >= 2 && rows.windows(2).all(|w| w[1].1 >= w[0].1);
    let margins: Vec<f64> = rows.iter().filter_map(|r| r.2).collect();
    let margin_rises =
        margins.len() == rows.len() && rows.len() >= 2 && margins.windows(2).all(|w| w[1] > w[0]);
    let sim_consistent = rows.windows(2).all(|w| w[1].3 >= w[0].3);
    findings.push(Finding {
        id: "e",
        paper: "For the smallest parcel farthest from the pivot, a higher belt speed makes capture more reliable.",
        divertsim: format!(
            "R_s from the trigger; corner test (capture margin α* − α_z): {}; full simulation: {}",
            rows.iter()
                .map(|(v, c, m, _)| format!(
                    "{v} m/s {} ({})",
                    if *c { "caught" } else { "escapes" },
                    m.map_or("no crossing".into(), |m| format!("{m:+.2}°"))
                ))
                .collect::<Vec<_>>()
                .join(", "),
            rows.iter()
                .map(|(v, _, _, d)| format!("{v} m/s {}", if *d { "diverted" } else { "not diverted" }))
                .collect::<Vec<_>>()
                .join(", "),
        ),
        figure: "capture.svg",
        verdict: match (captured_rises && margin_rises, sim_consistent) {
            (true, true) => Verdict::Holds,
            (true, false) | (false, true) if captured_rises || margin_rises => Verdict::Partly,
            _ => Verdict::DoesNotHold,
        },
    });

    // (f) Worst-case overload against the free-fall references, at the documented t_c.
    let ospeeds = if quick {
        linspace(0.65, 2.3, 4)
    } else {
        linspace(0.65, 2.3, 34)
    };
    // The searched worst case (issue 10) at every speed, over R_s 0–0.9 m and the
    // [design.search] class: the same question with every pose a parcel may arrive in.
    let search = SearchSettings {
        evaluations: if quick { 200 } else { 2400 },
        starts: if quick { 1 } else { 3 },
        population: if quick { 12 } else { 24 },
        refinement: if quick { 20 } else { 240 },
        seed: 1,
    };
    let over = overload::Overload::run(
        &inputs.machine,
        &overload::OverloadInputs {
            speeds: ospeeds.clone(),
            drop_heights: vec![0.2, 0.3],
            search: Some(((0.0, 0.9), search)),
        },
        &hooks,
    )?;
    files.push((
        "overload.csv".into(),
        overload::csv(&over).map_err(Error::io)?,
    ));
    let below = over.below();
    let largest_ratio = over
        .points
        .iter()
        .map(|p| p.worst.impulse / over.fall_impulses[1])
        .fold(0.0, f64::max);
    let searched = over.searched.as_deref().unwrap_or_default();
    let searched_max = searched.iter().map(|q| q.worst.value).fold(0.0, f64::max);
    let first_over = searched.iter().find(|q| q.worst.value > 1.0);
    findings.push(Finding {
        id: "f",
        paper: "At the tested belt speeds the overload stays below the 0.3 m free-fall reference.",
        divertsim: format!(
            "the paper's worst case (15 kg, tip strike at the largest α̇) at t_c = {} s, v = 0.65–2.3 m/s: largest S = {:.2} N·s, S/S_fall(0.3 m) ≤ {:.3}; below the 0.2 m reference too: {}. \
             The searched worst case (any parcel of the class, pose, arrival and R_s 0–0.9 m): S/S_fall up to {:.3}{}",
            over.cycle_time,
            over.max_impulse(),
            largest_ratio,
            if below[0] { "yes" } else { "no" },
            searched_max,
            match first_over {
                Some(q) => format!(", above the free fall from v = {:.2} m/s ({})", q.belt_speed, poses::pose_text_no_phase(&q.worst.pose)),
                None => ", below the free fall at every speed".into(),
            }
        ),
        figure: "overload.svg",
        verdict: match (below[1], first_over.is_none()) {
            (true, true) => Verdict::Holds,
            (true, false) => Verdict::Partly,
            _ => Verdict::DoesNotHold,
        },
    });

    // (g) Capacity over (t_c, S_d).
    let options = if quick {
        CapacityOptions {
            cycle_times: linspace(1.0, 1.5, 4),
            light_barriers: linspace(0.0, 0.9, 4),
            belt_speeds: linspace(1.0, 2.3, 3),
            start_step: 0.15,
            ..CapacityOptions::default()
        }
    } else {
        CapacityOptions::default()
    };
    let started = Instant::now();
    // The machine's own worst definition and margins: the map of the file as it stands,
    // bound as the command binds it (a torque margin needs the machine's torque limit).
    let map_inputs = capacity::Capacity::bind(
        capacity::CapacityInputs {
            grid: options,
            worst: inputs.machine.design.worst,
            margins: inputs.machine.design.margins,
            robust: None,
        },
        &inputs.machine,
    )?;
    let map = capacity::Capacity::run(&inputs.machine, &map_inputs, &hooks)?.map;
    let capacity_seconds = started.elapsed().as_secs_f64();
    files.push((
        "capacity.csv".into(),
        capacity::csv(&map).map_err(Error::io)?,
    ));
    findings.push(judge_capacity(&map));

    Ok(Replication {
        findings,
        files,
        paths_figures,
        trigger: tcurve,
        capture: cap,
        overload: over,
        capacity: map,
        capacity_worst: inputs.machine.design.worst,
        capacity_seconds,
    })
}

/// (g): W rises as t_c falls (along each S_d row, over feasible cells), as S_d falls (along
/// each t_c column), and the feasible region is a small part of the grid.
fn judge_capacity(map: &CapacityMap) -> Finding {
    let n_sd = map.options.light_barriers.len();
    let n_tc = map.options.cycle_times.len();
    let cell = |i: usize, j: usize| &map.cells[i * n_sd + j];
    let mut tc_pairs = (0, 0);
    let mut sd_pairs = (0, 0);
    for i in 0..n_tc {
        for j in 0..n_sd {
            let c = cell(i, j);
            if !c.feasible {
                continue;
            }
            if i + 1 < n_tc && cell(i + 1, j).feasible {
                tc_pairs.1 += 1;
                if c.capacity >= cell(i + 1, j).capacity - 1e-9 {
                    tc_pairs.0 += 1;
                }
            }
            if j + 1 < n_sd && cell(i, j + 1).feasible {
                sd_pairs.1 += 1;
                if c.capacity >= cell(i, j + 1).capacity - 1e-9 {
                    sd_pairs.0 += 1;
                }
            }
        }
    }
    let feasible = map.cells.iter().filter(|c| c.feasible).count();
    let settings_ok = map
        .settings
        .iter()
        .filter(|s| !s.feasible_starts.is_empty())
        .count();
    let best = map.best();
    // "Rises" in the trend sense: at least 90 % of neighbouring feasible pairs agree.
    let mostly = |(k, n): (usize, usize)| n > 0 && k as f64 >= 0.9 * n as f64;
    let tc_rises = mostly(tc_pairs);
    let sd_rises = mostly(sd_pairs);
    let narrow = (feasible as f64) < 0.5 * map.cells.len() as f64;
    Finding {
        id: "g",
        paper: "Capacity rises as t_c and S_d fall, and the best feasible region is narrow.",
        divertsim: format!(
            "{feasible} of {} cells feasible; {} of {} (t_c, v) settings have a feasible R_s; best W = {} at {}; W does not fall as t_c falls in {}/{} neighbouring feasible pairs, nor as S_d falls in {}/{}",
            map.cells.len(),
            settings_ok,
            map.settings.len(),
            best.map_or("-".into(), |b| format!("{:.0}/h", b.capacity)),
            best.map_or("-".into(), |b| format!(
                "t_c = {:.3} s, S_d = {:.3} m, v = {:.2} m/s, R_s = {:.3} m",
                b.cycle_time,
                b.light_barrier,
                b.belt_speed.unwrap_or(f64::NAN),
                b.start_position.unwrap_or(f64::NAN)
            )),
            tc_pairs.0,
            tc_pairs.1,
            sd_pairs.0,
            sd_pairs.1,
        ),
        figure: "capacity.svg",
        verdict: match (tc_rises, sd_rises, narrow) {
            (true, true, true) => Verdict::Holds,
            (false, false, false) => Verdict::DoesNotHold,
            _ => Verdict::Partly,
        },
    }
}

/// The findings as a readable table: each with its verdict, the paper's statement, divertsim's
/// figure and the figure file, then the capacity map's time.
pub fn findings_text(r: &Replication) -> String {
    let mut s = String::new();
    for f in &r.findings {
        s.push_str(&format!(
            "({}) {}\n    paper:     {}\n    divertsim: {}\n    figure:    {}\n",
            f.id,
            f.verdict.label().to_uppercase(),
            f.paper,
            f.divertsim,
            f.figure
        ));
    }
    s.push_str(&format!("capacity map: {:.1} s\n", r.capacity_seconds));
    s
}

/// findings.json (no timings: the same inputs give the same bytes).
pub fn findings_json(r: &Replication) -> Value {
    json!({
        "findings": r.findings.iter().map(|f| json!({
            "id": f.id,
            "paper": f.paper,
            "divertsim": f.divertsim,
            "figure": f.figure,
            "verdict": f.verdict.label(),
        })).collect::<Vec<_>>(),
    })
}

/// findings.md: the table docs/validation.md quotes.
pub fn findings_markdown(r: &Replication) -> String {
    let mut s = String::from(
        "| finding | the paper | divertsim | figure | verdict |\n|---|---|---|---|---|\n",
    );
    for f in &r.findings {
        s.push_str(&format!(
            "| ({}) | {} | {} | [{}]({}) | **{}** |\n",
            f.id,
            f.paper,
            f.divertsim.replace('|', "/"),
            f.figure,
            f.figure,
            f.verdict.label()
        ));
    }
    s
}
