//! report.html of a line run (`divertsim line --out`): the rates and throughput of every
//! point, the throughput curve (with a sweep), the animated line view of the first parcels
//! (assets/line/line.js: the belt from above, the arms through their cycles, the parcels
//! coloured by outcome), and the first failures, each linked to its own animated run
//! (runs/parcel_N.html, the page of [`crate::run::single`]).

use crate::run::{escape, script_json, single, table};
use crate::Pages;
use divertsim_api::analyses::line::{failures, parcel_file, trace, LineStudy, OUTCOME_LEGEND};
use divertsim_api::config::to_toml;
use divertsim_core::analysis::population::reliability::CONFIDENCE;
use divertsim_core::model::drive::ArmDrive;
use serde_json::{json, Value};

/// Parcels in the animated view.
const VIEW_PARCELS: u64 = 40;
/// Failures linked to their own runs.
const LINKED_FAILURES: usize = 20;
/// Spacing of an arm's cycle shape in the view's data \[s].
const SHAPE_STEP: f64 = 0.005;

const SCRIPT: &str = include_str!("../assets/line/line.js");

/// report.html and runs/parcel_N.html of a line study; `throughput` the SVG text of its
/// throughput curve, if drawn (inlined).
pub fn pages(study: &LineStudy, throughput: Option<&str>) -> Result<Pages, String> {
    let mut pages = Pages::new();
    let Some(first) = study.results.first() else {
        return Ok(pages);
    };
    // The failures' own runs.
    let mut links = std::collections::BTreeMap::new();
    let mut rows = String::new();
    for p in failures(first).take(LINKED_FAILURES) {
        let (Some(s), Some(file)) = (first.point.line.scenario_of(p), parcel_file(first, p)) else {
            continue;
        };
        let heading = format!("Parcel {} of a line run: {}", p.index, p.outcome.label());
        let toml = to_toml(&file, &heading).map_err(|e| e.to_string())?;
        let r = divertsim_core::sim::simulate(&s);
        let name = format!("runs/parcel_{}.html", p.index);
        pages.push((name.clone(), single(&s, &r, &toml)));
        links.insert(p.index, name.clone());
        rows += &format!(
            "<tr><td><a href=\"{name}\">{}</a></td><td>{}</td><td>{}</td><td>{}</td><td>{:.3} × {:.3}</td><td>{:.3}</td><td>{:.1}</td><td>{:.3}</td></tr>",
            p.index,
            escape(p.outcome.label()),
            p.outcome.reason().unwrap_or(""),
            p.decided_at.map_or("end".into(), |d| (d + 1).to_string()),
            p.length,
            p.width,
            p.offset,
            p.angle.to_degrees(),
            p.overload_ratio
        );
    }
    // The animated stretch.
    let t = trace(first, &study.options, VIEW_PARCELS).map_err(|e| e.to_string())?;
    let line = &first.point.line;
    let diverters: Vec<Value> = line
        .diverters
        .iter()
        .zip(&t.cycles)
        .map(|(d, cycles)| {
            let m = &d.setting.machine;
            let shape: Vec<f64> = match ArmDrive::new(&m.drive, m.cycle_time) {
                Ok(drive) => (0..=(m.cycle_time / SHAPE_STEP).ceil() as usize)
                    .map(|i| drive.state((i as f64 * SHAPE_STEP).min(m.cycle_time)).angle)
                    .collect(),
                Err(_) => vec![0.0, 0.0],
            };
            json!({"x": d.position, "arm": m.arm_length, "dt": SHAPE_STEP, "shape": shape, "cycles": cycles})
        })
        .collect();
    let by_index: std::collections::HashMap<u64, &divertsim_core::analysis::line::LineParcel> =
        first.parcels.iter().map(|p| (p.index, p)).collect();
    let parcels: Vec<Value> = t
        .parcels
        .iter()
        .map(|path| {
            let p = by_index.get(&path.index);
            json!({
                "i": path.index,
                "a": path.length,
                "b": path.width,
                "k": path.keyframes,
                "gone": path.gone,
                "outcome": p.map_or("passed", |p| p.outcome.label()),
                "bad": p.is_some_and(|p| !p.outcome.correct()),
                "link": links.get(&path.index),
            })
        })
        .collect();
    let times = t
        .parcels
        .iter()
        .flat_map(|p| p.keyframes.iter().map(|k| k[0]));
    let (t0, t1) = times.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
        (a.min(x), b.max(x))
    });
    let last = line
        .diverters
        .last()
        .map_or(0.0, |d| d.position + d.setting.machine.arm_length);
    let data = json!({
        "belt_width": line.diverters[0].setting.machine.belt_width,
        "x0": -3.0, "x1": last + 1.5,
        "t0": if t0.is_finite() { t0 } else { 0.0 },
        "t1": if t1.is_finite() { t1 } else { 1.0 },
        "diverters": diverters,
        "parcels": parcels,
    });
    // The rates of every point.
    let mut points = String::new();
    for r in &study.results {
        let tl = &r.tally;
        let rates: Vec<String> = OUTCOME_LEGEND
            .iter()
            .map(|(k, _)| {
                let p = tl.rate(k, CONFIDENCE);
                format!("{:.2} %", 100.0 * p.estimate)
            })
            .collect();
        points +=
            &format!(
            "<tr><td>{}</td><td>{}</td><td>{:.0}</td><td>{:.0}</td><td>{:.0}</td><td>{}</td></tr>",
            escape(&r.point.point.value),
            tl.parcels,
            tl.arrival_rate(),
            tl.line_throughput(),
            r.point.line.diverters.iter().map(|d| d.paper_capacity()).sum::<f64>(),
            rates.join("</td><td>")
        );
    }
    let heads: String = OUTCOME_LEGEND
        .iter()
        .map(|(k, m)| format!("<th title=\"{}\">{}</th>", escape(m), escape(k)))
        .collect();
    let curve = throughput
        .and_then(|s| s.find("<svg").map(|i| s[i..].to_string()))
        .map_or(String::new(), |svg| {
            format!("<h2>Throughput</h2><div>{svg}</div>")
        });
    let legend: String = OUTCOME_LEGEND
        .iter()
        .map(|(k, m)| format!("<li><b>{}</b>: {}</li>", escape(k), escape(m)))
        .collect();
    let html = format!(
        "<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\"><title>divertsim line</title>\
         <style>body{{font:14px/1.4 system-ui,sans-serif;max-width:1400px;margin:0 auto;padding:12px 18px}}\
         table{{border-collapse:collapse}}td,th{{border:1px solid #dde;padding:2px 8px;text-align:left}}\
         svg{{max-width:100%;height:auto}}#line-canvas{{width:100%;border:1px solid #ccd}}</style></head><body>\
         <h1>divertsim line</h1>\
         <h2>Rates</h2><table><tr><th>point</th><th>parcels</th><th>arrivals [1/h]</th><th>throughput [1/h]</th><th>paper's W [1/h]</th>{heads}</tr>{points}</table>\
         <ul>{legend}</ul>\
         <h2>The line</h2><p>The first {} parcels of the stream{}: chutes above the belt, arms in blue, each parcel \
         coloured by its outcome (a red outline: not where it was bound; click one to open its run).</p>\
         <p><button id=\"line-play\">pause</button> speed <select id=\"line-speed\"><option value=\"0.25\">¼×</option>\
         <option value=\"0.5\" selected>½×</option><option value=\"1\">1×</option></select> \
         <input id=\"line-time\" type=\"range\" style=\"width:60%\"> <span id=\"line-clock\"></span></p>\
         <canvas id=\"line-canvas\"></canvas>\
         <h2>Failures</h2>{failures}\
         {curve}\
         <script type=\"application/json\" id=\"line-data\">{}</script><script>{SCRIPT}</script></body></html>",
        t.parcels.len(),
        if study.results.len() > 1 { " (the first sweep point)" } else { "" },
        script_json(&data),
        failures = if rows.is_empty() {
            table(&[], "", "None: every parcel of the stream went where it was bound.")
        } else {
            format!(
                "<p>The first {} parcels not where they were bound; each opens its own run, with every stroke near it.</p>{}",
                links.len(),
                table(
                    &["parcel", "outcome", "reason", "diverter", "a × b [m]", "ΔP [m]", "φ [deg]", "S/S_fall"],
                    &rows,
                    "",
                )
            )
        },
    );
    pages.push(("report.html".to_string(), html));
    Ok(pages)
}
