//! report.html of a reliability study (`divertsim reliability --out`): the rates with
//! their intervals per point, the failure breakdowns, the study's plots (inlined SVG) and
//! the first failed samples, each linked to its own animated run (runs/sample_P_N.html,
//! the page of [`crate::run::single`]).

use crate::run::{escape, single, table};
use crate::Pages;
use divertsim_api::analyses::reliability::{setting_line, Point, CONFIDENCE};
use divertsim_core::analysis::population::reliability::{PointResult, SampleRun, StartRule};
use serde_json::Value;

/// The study's plots that its page shows, in order (the files `--out` draws).
pub const PLOTS: [&str; 5] = [
    "failure_rate.svg",
    "divert_reserve.svg",
    "overload_ratio.svg",
    "load_spectrum.svg",
    "sweep.svg",
];

/// report.html: the summary, the breakdown, the plots (`plots`: (file name, SVG text) of
/// those drawn, inlined) and the first failed samples, each linked to its own animated run
/// (runs/sample_P_N.html, among the pages too).
pub fn pages(
    points: &[Point],
    results: &[(PointResult, StartRule)],
    failed: &[(usize, SampleRun)],
    summary: &Value,
    plots: &[(&str, String)],
) -> Pages {
    let mut pages = Pages::new();
    let mut rows = String::new();
    for (point, f) in failed {
        let p = &points[*point];
        let s = f.draw.scenario(&p.loaded.scenario, f.start_position);
        let r = divertsim_core::sim::simulate(&s);
        let d = &f.draw;
        let inputs =
            format!(
            "sample {} of the mix (seed {}{}): parcel {} × {} × {} m, {} kg, ΔP {} m, φ {:.2}°, \
             arrival Δv {} m/s, ω {} rad/s, trigger error {} s; μ_b {}, μ_a {}, e* {}; R_s {} m",
            d.index,
            p.seed,
            if p.value.is_empty() { String::new() } else { format!(", sweep point {}", p.value) },
            d.length, d.width, d.height, d.mass, d.offset, d.angle.to_degrees(), d.speed, d.spin,
            d.phase,
            d.belt_friction.map_or("(scenario's)".to_string(), |m| m.to_string()),
            d.arm_friction, d.restitution, s.machine.start_position
        );
        let name = format!("runs/sample_{}_{}.html", point, d.index);
        pages.push((name.clone(), single(&s, &r, &inputs)));
        rows += &format!(
            "<tr><td><a href=\"{name}\">{}</a></td><td>{}</td><td>{}</td><td>{:.3} × {:.3}</td><td>{:.3}</td><td>{:.1}</td><td>{:.4}</td><td>{:.3}</td></tr>",
            d.index,
            escape(&p.value),
            f.reason().unwrap_or(""),
            d.length,
            d.width,
            d.offset,
            d.angle.to_degrees(),
            f.reserve,
            f.overload_ratio
        );
    }
    let mut points_html = String::new();
    let mut loads_html = String::new();
    for (i, (p, (r, trigger))) in points.iter().zip(results).enumerate() {
        let t = &r.tally;
        let (dv, ov) = (t.divert_rate(CONFIDENCE), t.overload_rate(CONFIDENCE));
        let tip = t.tipping_rate(CONFIDENCE);
        if let Some((_, l)) = &t.loads.largest {
            let file = divertsim_api::analyses::population::largest_stroke_name(points.len(), i);
            loads_html += &format!(
                "<tr><td>{}</td><td>{}</td><td>{:.2}</td><td><a href=\"{file}\">sample {}</a></td><td>{}</td><td>{:.4}</td></tr>",
                escape(&p.value),
                t.loads.strokes,
                l.arm_peak_torque.unwrap_or(f64::NAN),
                l.draw.index,
                t.loads
                    .torque_spectrum
                    .as_ref()
                    .and_then(|sp| quantile_bin(sp, 0.99))
                    .map_or("–".to_string(), |(lo, hi)| format!("{lo}–{hi}")),
                t.loads.largest_strike(),
            );
        }
        let list = |m: &std::collections::BTreeMap<String, u64>| {
            m.iter()
                .map(|(k, n)| format!("{} {n}", escape(k)))
                .collect::<Vec<_>>()
                .join(", ")
        };
        points_html += &format!(
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{:.5} [{:.5}, {:.5}]</td><td>{:.5} [{:.5}, {:.5}]</td><td>{:.5} [{:.5}, {:.5}]</td><td>{:.0}</td><td>{}</td><td>{}</td></tr>",
            escape(&p.value),
            escape(&setting_line(p, trigger)),
            t.samples,
            dv.estimate, dv.lower, dv.upper,
            ov.estimate, ov.lower, ov.upper,
            tip.estimate, tip.lower, tip.upper,
            t.capacity(),
            list(&t.by_reason),
            list(&t.by_final_stage)
        );
    }
    let mut inlined = String::new();
    for (name, svg) in plots {
        let svg = svg.find("<svg").map_or("", |i| &svg[i..]);
        inlined += &format!(
            "<h2>{}</h2><div style=\"overflow:auto\">{svg}</div>",
            escape(name)
        );
    }
    let plots = inlined;
    let html = format!(
        "<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\"><title>divertsim reliability</title>\
         <style>body{{font:14px/1.4 system-ui,sans-serif;max-width:1400px;margin:0 auto;padding:12px 18px}}\
         table{{border-collapse:collapse}}td,th{{border:1px solid #dde;padding:2px 8px;text-align:left}}\
         svg{{max-width:100%;height:auto}}</style></head><body>\
         <h1>divertsim reliability</h1><p>{}</p>\
         <h2>Rates (95 % Clopper–Pearson intervals)</h2><table><tr><th>point</th><th>setting</th><th>samples</th>\
         <th>divert rate</th><th>overload rate</th><th>tipping rate</th><th>W [1/h]</th><th>failures by reason</th><th>by final stage</th></tr>{points_html}</table>\
         <h2>Arm loads</h2><p>Each stroke's peak drive torque at the arm and each strike's angular impulse on it; the whole spectra, as counts per 10<sup>6</sup> strokes, are in load_spectrum.csv (docs/model.md §12c).</p>{loads}\
         <h2>Failed samples</h2>{failures}\
         {plots}</body></html>",
        escape(summary["tool"].as_str().unwrap_or("")),
        loads = table(
            &[
                "point",
                "strokes",
                "largest peak drive torque [N·m]",
                "its stroke (scenario file)",
                "the 99 % quantile's bin [N·m]",
                "largest strike [N·m·s]",
            ],
            &loads_html,
            "No stroke loaded the arm (or the scenario has no arm).",
        ),
        failures = if rows.is_empty() {
            table(&[], "", "None: every sample diverted within the overload limit.")
        } else {
            format!(
                "<p>The first {} failed samples; each opens its own animated run.</p>{}",
                failed.len(),
                table(
                    &["sample", "point", "reason", "a × b [m]", "ΔP [m]", "φ [deg]", "reserve [m]", "S/S_fall"],
                    &rows,
                    "",
                )
            )
        },
    );
    pages.push(("report.html".to_string(), html));
    pages
}

/// The bin (lower, upper edge) where the spectrum's cumulative share first reaches `q`
/// (`None` if it lies above the last edge).
fn quantile_bin(sp: &divertsim_core::stats::histogram::Spectrum, q: f64) -> Option<(f64, f64)> {
    let total = sp.total() as f64;
    let mut seen = 0.0;
    for k in 0..sp.count.len() {
        seen += sp.count[k] as f64;
        if total > 0.0 && seen >= q * total {
            return Some((sp.lower(k), sp.upper[k]));
        }
    }
    None
}
