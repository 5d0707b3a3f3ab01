//! Self-contained HTML reports: one file that opens offline, with the animated top view
//! (canvas: belt, guide, pivot, the arm at its angle, the parcel outline and centre path,
//! active contacts, strikes flashed with their impulse), controls (play/pause, speed
//! 0.1–2×, a time scrubber, frame steps, the time and stage), linked plots (uPlot, inlined
//! with its licence: α(t), velocity and spin, strikes against the free fall, the stage
//! timeline; hovering a plot moves the animation) and a summary with the resolved scenario.
//!
//! The page exposes `window.divertsim` (seek, pose, play, pause, errors) for tests; with
//! `#selftest=t1,t2,…` in its address it plays a moment, seeks to each time and prints the
//! drawn poses into `<pre id="selftest">`.

use divertsim_core::model::params::{NearSide, Scenario};
use divertsim_core::sim::{SimResult, Stage};
use serde_json::{json, Value};

use divertsim_figures::charts::{short, PALETTE};
use divertsim_figures::plot::stage_color;

const TEMPLATE: &str = include_str!("../assets/report/report.html");
const VIEWER: &str = include_str!("../assets/report/viewer.html");
use crate::assets::{REPORT_CSS as CSS, REPORT_JS as JS, UPLOT_CSS, UPLOT_JS};
const UPLOT_VERSION: &str = "1.6.32";

/// One run shown in a report.
pub struct ReportRun<'a> {
    pub label: String,
    pub scenario: &'a Scenario,
    pub result: &'a SimResult,
    /// A measured marker track to show with the run: (simulation time, x, y) [s, m].
    pub measured: Vec<(f64, f64, f64)>,
}

fn hex(c: plotters::style::RGBColor) -> String {
    format!("#{:02x}{:02x}{:02x}", c.0, c.1, c.2)
}

/// Text safe inside HTML (element content and quoted attributes).
pub fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
        .replace('\'', "&#39;")
}

/// A table with its header row, or, when it has no rows, the sentence `none` in its place:
/// a report never shows a header over nothing.
pub fn table(headers: &[&str], rows: &str, none: &str) -> String {
    if rows.is_empty() {
        return format!("<p class=\"none\">{}</p>", escape(none));
    }
    let head: String = headers
        .iter()
        .map(|h| format!("<th>{}</th>", escape(h)))
        .collect();
    format!("<table><tr>{head}</tr>{rows}</table>")
}

/// JSON text safe inside a `<script>` element: `<`, `>` and `&` (which occur only inside
/// its strings) as `\u` escapes, so that no name can close the element (`</script>`) or
/// switch the parser's script states (`<!--<script>`).
pub fn script_json(v: &Value) -> String {
    v.to_string()
        .replace('<', "\\u003c")
        .replace('>', "\\u003e")
        .replace('&', "\\u0026")
}

/// `template` with each `{{NAME}}` of `fields` replaced by its value, in one pass over the
/// template: a value is never searched for placeholders (a run named `{{BODY}}` stays that
/// text), and an unknown `{{...}}` is left as it is.
pub fn fill(template: &str, fields: &[(&str, &str)]) -> String {
    let mut out =
        String::with_capacity(template.len() + fields.iter().map(|f| f.1.len()).sum::<usize>());
    let mut rest = template;
    while let Some(at) = rest.find("{{") {
        out.push_str(&rest[..at]);
        let after = &rest[at + 2..];
        match after.find("}}").and_then(|end| {
            fields
                .iter()
                .find(|f| f.0 == &after[..end])
                .map(|f| (end, f.1))
        }) {
            Some((end, value)) => {
                out.push_str(value);
                rest = &after[end + 2..];
            }
            None => {
                out.push_str("{{");
                rest = after;
            }
        }
    }
    out.push_str(rest);
    out
}

/// A run's data for the page.
fn run_json(k: usize, r: &ReportRun<'_>) -> Value {
    let tr = &r.result.trajectory;
    let col = |f: &dyn Fn(&divertsim_core::sim::Sample) -> f64| -> Vec<f64> {
        tr.iter().map(f).collect()
    };
    let stage_index = |s: Stage| Stage::ALL.iter().position(|x| *x == s).unwrap_or(0);
    json!({
        "label": r.label,
        "color": hex(PALETTE[k % PALETTE.len()]),
        "length": r.scenario.parcel.length,
        "width": r.scenario.parcel.width,
        "arm_length": r.scenario.machine.arm_length,
        "t": col(&|s| s.state.t),
        "x": col(&|s| s.state.x),
        "y": col(&|s| s.state.y),
        "phi": col(&|s| s.state.phi),
        "alpha": col(&|s| s.arm_angle),
        // M_d(t), the drive's torque on the arm (null without an arm).
        "drive_torque": r.result.drive_torque_series(r.scenario),
        "vx": col(&|s| s.state.vx),
        "vy": col(&|s| s.state.vy),
        "omega": col(&|s| s.state.omega),
        "stage": tr.iter().map(|s| stage_index(s.stage)).collect::<Vec<_>>(),
        "contacts": tr.iter().map(|s| s.contacts.iter().flatten().copied().collect::<Vec<[f64; 2]>>()).collect::<Vec<_>>(),
        "impacts": r.result.impacts.iter().map(|i| json!({
            "t": i.t, "impulse": i.impulse, "stage": i.stage.label(), "point": i.point,
        })).collect::<Vec<_>>(),
        "fall_impulse": r.result.overload.fall_impulse,
        "measured": r.measured.iter().map(|m| [m.0, m.1, m.2]).collect::<Vec<_>>(),
    })
}

/// The page data.
pub fn data(runs: &[ReportRun<'_>]) -> Value {
    let first = runs.first().map(|r| r.scenario);
    json!({
        "machine": {
            "belt_width": first.map_or(0.7, |s| s.machine.belt_width),
            "arm_length": runs.iter().map(|r| r.scenario.machine.arm_length).fold(0.0, f64::max),
            "guide_everywhere": first.is_some_and(|s| s.machine.near_side == NearSide::Guide),
            "arm_inertia": first.map_or(0.0, |s| s.machine.arm_inertia),
        },
        "drop_height": first.map_or(0.3, |s| s.limits.drop_height),
        "stages": Stage::ALL.iter().map(|s| s.label()).collect::<Vec<_>>(),
        "stage_colors": Stage::ALL.iter().map(|s| hex(stage_color(*s))).collect::<Vec<_>>(),
        "runs": runs.iter().enumerate().map(|(k, r)| run_json(k, r)).collect::<Vec<_>>(),
    })
}

/// A table of each run's outcome, stages and strikes (HTML).
pub fn summary_html(runs: &[ReportRun<'_>]) -> String {
    let mut s = String::from(
        "<table><tr><th>run</th><th>outcome</th><th>stages</th><th>strikes</th><th>largest S/S_fall</th><th>max lateral [m]</th><th>tipping margin</th><th>peak drive torque [N·m]</th></tr>",
    );
    for r in runs {
        let res = r.result;
        let margin = res.tipping.margin;
        s +=
            &format!(
            "<tr><td>{}</td><td>{}{}</td><td>{}</td><td>{}</td><td>{:.3}</td><td>{:.4}</td><td>{}</td><td>{}</td></tr>",
            escape(&r.label),
            res.outcome.label(),
            res.outcome
                .reason()
                .map(|x| format!(" ({})", escape(&x)))
                .unwrap_or_default(),
            res.stages.iter().map(|x| x.label()).collect::<Vec<_>>().join(" → "),
            res.impacts.len(),
            res.overload.overload_ratio,
            res.max_lateral,
            // Below 1 an edge lifted (docs/model.md §12a); nothing loaded it sideways: –.
            if margin.is_finite() { format!("{margin:.3}") } else { "–".into() },
            res.arm_loads(r.scenario)
                .map_or("–".into(), |l| format!("{:.2}", l.peak_torque))
        );
    }
    let all: Vec<Stage> = runs
        .iter()
        .flat_map(|r| r.result.stages.iter().copied())
        .collect();
    s + &format!(
        "</table><p class=\"legend\">Stages: {}.</p>",
        escape(&divertsim_core::sim::stage_legend(&all))
    )
}

/// The setting line of a scenario: v, t_c, R_s, ΔP, parcel (numbers to 4 decimals).
pub fn setting_line(s: &Scenario) -> String {
    let p = &s.parcel;
    format!(
        "v = {} m/s, t_c = {} s, R_s = {} m; parcel {} × {} m, {} kg at ΔP = {} m, φ = {:.1}°",
        short(s.machine.belt_speed),
        short(s.machine.cycle_time),
        short(s.machine.start_position),
        short(p.length),
        short(p.width),
        short(p.mass),
        short(p.offset),
        p.angle.to_degrees()
    )
}

/// The run viewer's elements (the top view, its controls, the stage timeline, the plots),
/// which report.js draws: the report's page and the studio's. `side` (HTML) ends the plots'
/// grid.
pub fn viewer(side: &str) -> String {
    fill(VIEWER, &[("SIDE", side)])
}

/// The whole page. `side` goes beside the plots, `body` below them (HTML, escaped by the
/// caller).
pub fn html(title: &str, subtitle: &str, runs: &[ReportRun<'_>], side: &str, body: &str) -> String {
    let data = script_json(&data(runs));
    let viewer = viewer(&format!("<div>{side}</div>"));
    fill(
        TEMPLATE,
        &[
            ("VIEWER", &viewer),
            ("UPLOT_JS", UPLOT_JS),
            ("UPLOT_CSS", UPLOT_CSS),
            ("UPLOT_VERSION", UPLOT_VERSION),
            ("CSS", CSS),
            ("JS", JS),
            ("DATA", &data),
            ("TITLE", &escape(title)),
            ("SUBTITLE", &escape(subtitle)),
            ("BODY", body),
        ],
    )
}

/// The report of one simulated run, with its summary and resolved scenario.
pub fn single(scenario: &Scenario, result: &SimResult, scenario_toml: &str) -> String {
    let runs = [ReportRun {
        label: "parcel".into(),
        scenario,
        result,
        measured: Vec::new(),
    }];
    let o = &result.overload;
    let side = format!(
        "<h2>Summary</h2>{}<p>Largest impulse S = {:.3} N·s against S_fall = {:.3} N·s from H₀ = {} m \
         (S/S_fall = {:.3}, equivalent drop {:.3} m).</p>",
        summary_html(&runs),
        o.max_impulse,
        o.fall_impulse,
        scenario.limits.drop_height,
        o.overload_ratio,
        o.equivalent_drop_height
    );
    let strikes: String = result
        .impacts
        .iter()
        .map(|i| {
            format!(
                "<tr><td>{:.4}</td><td>{}</td><td>{}</td><td>{:.3}</td><td>{:.3}</td><td>{:.3}</td></tr>",
                i.t,
                i.stage.label(),
                i.obstacle.label(),
                i.approach_speed,
                i.impulse,
                i.impulse / o.fall_impulse
            )
        })
        .collect();
    let body = format!(
        "<h2>Strikes</h2>{}\
         <h2>Scenario (resolved, every input)</h2><pre class=\"scenario\">{}</pre>",
        table(
            &[
                "t [s]",
                "stage",
                "obstacle",
                "approach [m/s]",
                "S [N·s]",
                "S/S_fall"
            ],
            &strikes,
            "No strike: the arm pushed the parcel without an impact, or never reached it."
        ),
        escape(scenario_toml)
    );
    // The verdict with its reason (a jam, a tip-over, …), then the stages it went through.
    let title = format!(
        "divertsim: {}{} — {}",
        result.outcome.short_verdict(),
        result
            .overload
            .exceeds_text()
            .map(|x| format!(", {x}"))
            .unwrap_or_default(),
        result
            .stages
            .iter()
            .map(|s| s.label())
            .collect::<Vec<_>>()
            .join(" → ")
    );
    html(&title, &setting_line(scenario), &runs, &side, &body)
}

/// The report of several runs animated together, each with its colour and toggle.
pub fn multi(title: &str, runs: &[ReportRun<'_>]) -> String {
    let settings: String = runs
        .iter()
        .map(|r| {
            format!(
                "<tr><td>{}</td><td>{}</td></tr>",
                escape(&r.label),
                escape(&setting_line(r.scenario))
            )
        })
        .collect();
    let side = format!("<h2>Summary</h2>{}", summary_html(runs));
    let body = format!("<h2>Settings</h2><table>{settings}</table>");
    html(
        title,
        &format!(
            "{} runs, animated together; the checkboxes hide and show each",
            runs.len()
        ),
        runs,
        &side,
        &body,
    )
}
