//! Reports never show a header over nothing (issue 27, B9): every `<table>` of a report has
//! at least one data row, and a section with nothing to list says so in a sentence.

use crate::common::divertsim;
use std::path::Path;

/// Every table of `html` has a header row and at least one data row.
fn assert_no_empty_table(html: &str, what: &str) {
    let mut rest = html;
    let mut tables = 0;
    while let Some(i) = rest.find("<table") {
        let end = rest[i..].find("</table>").expect("a closed table") + i;
        let rows = rest[i..end].matches("<tr").count();
        assert!(
            rows >= 2,
            "{what}: a table with {rows} row(s): {}",
            &rest[i..end]
        );
        tables += 1;
        rest = &rest[end..];
    }
    assert!(tables >= 1, "{what}: no table at all");
}

fn report(dir: &Path, args: &[&str]) -> String {
    let out = dir.join(args[0]);
    divertsim()
        .args(args)
        .args(["-q", "--out"])
        .arg(&out)
        .assert()
        .success();
    std::fs::read_to_string(out.join("report.html")).unwrap()
}

#[test]
fn reports_without_failures_say_none_instead_of_an_empty_table() {
    let tmp = tempfile::tempdir().unwrap();
    // Four-metre gaps, every parcel to the one diverter: none fails.
    let line = report(
        tmp.path(),
        &[
            "line",
            "--parcels",
            "30",
            "--set",
            "line.gap_target=4",
            "--set",
            "line.share=1",
        ],
    );
    assert_no_empty_table(&line, "line");
    assert!(line.contains("None: every parcel of the stream went where it was bound."));
    assert!(!line.contains("The first 0"));
    // The paper's parcel class, no taller than 0.15 m (taller narrow ones tip), at the
    // paper's setting: 30 samples all divert.
    let mix = concat!(env!("CARGO_MANIFEST_DIR"), "/../../configs/paper/mix.toml");
    let rel = report(
        tmp.path(),
        &[
            "reliability",
            mix,
            "--samples",
            "30",
            "--set",
            "mix.height={kind=\"uniform\", min=0.1, max=0.15}",
        ],
    );
    assert_no_empty_table(&rel, "reliability");
    assert!(rel.contains("None: every sample diverted within the overload limit."));
    assert!(!rel.contains("The first 0"));
}

#[test]
fn reports_with_rows_keep_their_tables() {
    let tmp = tempfile::tempdir().unwrap();
    let run = report(tmp.path(), &["simulate"]);
    assert_no_empty_table(&run, "simulate");
    assert!(run.contains("<th>S/S_fall</th>"), "the strikes table");
    // Two-metre gaps on the line preset: some parcels find the arm busy.
    let line = report(tmp.path(), &["line", "--parcels", "60"]);
    assert_no_empty_table(&line, "line");
    assert!(line.contains("parcels not where they were bound"));
}
