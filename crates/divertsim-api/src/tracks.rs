//! Track files: a marker tracked on video, as CSV. A header names the columns: `t` (or
//! `time`, seconds) or `frame` (a frame number, with `[camera].frame_rate`), and the marker
//! position `u, v` (pixels) or `x, y` (machine metres). Lines starting with `#` are
//! comments; a comment `# set KEY=VALUE` states a scenario override of the experiment
//! filmed (its parcel, speed, R_s), applied on top of the scenario the command is given. A
//! comment `# arm_start = T` (or `T ± W`, `T +- W`) states the arm start on the video, in the
//! time column's unit (seconds, or frames): it pins the alignment (or bounds it to ± W).
//!
//! Checks, each reported with its line: times must increase; a gap of more than
//! `max_gap` frame intervals is an error (a lost stretch of tracking); pixel positions must
//! lie on the image; at least [`MIN_POINTS`] points.

use divertsim_core::analysis::measurement::track::{ArmStart, CameraMap, Track};
use glam::DVec2;
use std::path::Path;

/// Fewest points a track may have.
pub const MIN_POINTS: usize = 5;

/// A read track.
#[derive(Debug, Clone, PartialEq)]
pub struct TrackFile {
    /// The `# set KEY=VALUE` overrides, in order.
    pub sets: Vec<String>,
    /// Times \[s] and positions as read (pixels or metres).
    pub times: Vec<f64>,
    pub positions: Vec<[f64; 2]>,
    /// Whether the positions are pixels.
    pub pixels: bool,
    /// The arm start stated by `# arm_start`, in seconds.
    pub arm_start: Option<ArmStart>,
}

/// Read and check a track file.
pub fn read(
    path: &Path,
    frame_rate: f64,
    image: [f64; 2],
    max_gap: f64,
) -> Result<TrackFile, String> {
    let text = read_text(path)?;
    // A spreadsheet's byte-order mark is not part of the header.
    let text = text.strip_prefix('\u{feff}').unwrap_or(&text);
    let mut sets = Vec::new();
    let mut arm_start: Option<(f64, f64)> = None;
    let mut header: Option<Vec<String>> = None;
    let mut cols = (0usize, 0usize, 0usize, false, false); // (time, a, b, frames, pixels)
    let mut times = Vec::new();
    let mut positions = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line_no = i + 1;
        let line = raw.trim();
        if line.is_empty() {
            continue;
        }
        if let Some(c) = line.strip_prefix('#') {
            if let Some(set) = set_line(c).map_err(|e| format!("line {line_no}: {e}"))? {
                sets.push(set);
            }
            if let Some(pin) = arm_start_line(c).map_err(|e| format!("line {line_no}: {e}"))? {
                if arm_start.is_some() {
                    return Err(format!("line {line_no}: `# arm_start` is given twice"));
                }
                arm_start = Some(pin);
            }
            continue;
        }
        let cells: Vec<&str> = line
            .split(',')
            .map(|c| c.trim().trim_matches('"').trim())
            .collect();
        let Some(h) = &header else {
            let names: Vec<String> = cells.iter().map(|c| c.to_ascii_lowercase()).collect();
            let find = |n: &[&str]| names.iter().position(|c| n.contains(&c.as_str()));
            let time = find(&["t", "time"]).map(|k| (k, false));
            let frame = find(&["frame"]).map(|k| (k, true));
            let Some((tc, frames)) = time.or(frame) else {
                return Err(format!(
                    "line {line_no}: the header needs a time column (t or time [s]) or a frame column"
                ));
            };
            let (a, b, pixels) = match (find(&["u"]), find(&["v"]), find(&["x"]), find(&["y"])) {
                (Some(u), Some(v), _, _) => (u, v, true),
                (_, _, Some(x), Some(y)) => (x, y, false),
                _ => {
                    return Err(format!(
                    "line {line_no}: the header needs the marker position: u, v [px] or x, y [m]"
                ))
                }
            };
            cols = (tc, a, b, frames, pixels);
            header = Some(names);
            continue;
        };
        if cells.len() != h.len() {
            return Err(format!(
                "line {line_no}: {} fields where the header has {}",
                cells.len(),
                h.len()
            ));
        }
        let num = |k: usize, name: &str| -> Result<f64, String> {
            cells[k]
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| format!("line {line_no}, column {name}: not a finite number"))
        };
        let (tc, a, b, frames, pixels) = cols;
        let t = num(tc, if frames { "frame" } else { "t" })?;
        let t = if frames { t / frame_rate } else { t };
        let p = [
            num(a, if pixels { "u" } else { "x" })?,
            num(b, if pixels { "v" } else { "y" })?,
        ];
        if pixels && !((0.0..=image[0]).contains(&p[0]) && (0.0..=image[1]).contains(&p[1])) {
            return Err(format!(
                "line {line_no}: pixel ({}, {}) is off the {}×{} image (camera.image_size)",
                p[0], p[1], image[0], image[1]
            ));
        }
        if let Some(&last) = times.last() {
            if t <= last {
                return Err(format!(
                    "line {line_no}: time {t} s does not follow {last} s; times must increase"
                ));
            }
            if t - last > max_gap / frame_rate + 1e-9 {
                return Err(format!(
                    "line {line_no}: a gap of {:.4} s after {last} s, more than {max_gap} frame intervals (lost tracking?); fill or split the track, or raise --max-gap",
                    t - last
                ));
            }
        }
        times.push(t);
        positions.push(p);
    }
    if header.is_none() {
        return Err("no header line".into());
    }
    if times.len() < MIN_POINTS {
        return Err(format!(
            "{} points; allowed: at least {MIN_POINTS}",
            times.len()
        ));
    }
    let unit = if cols.3 { frame_rate } else { 1.0 };
    Ok(TrackFile {
        sets,
        times,
        positions,
        pixels: cols.4,
        arm_start: arm_start.map(|(time, within)| ArmStart {
            time: time / unit,
            within: within / unit,
        }),
    })
}

/// The arm start of a comment `# arm_start = T` or `T ± W` / `T +- W` (in the time column's
/// unit), if it is one.
fn arm_start_line(comment: &str) -> Result<Option<(f64, f64)>, String> {
    let c = comment.trim();
    let Some(rest) = c.strip_prefix("arm_start") else {
        return Ok(None);
    };
    let Some(value) = rest.trim_start().strip_prefix('=') else {
        return Ok(None);
    };
    let bad = || {
        format!(
            "`# arm_start ={value}`: allowed: `# arm_start = T` or `# arm_start = T ± W` (W ≥ 0, in the time column's unit)"
        )
    };
    let value = value.trim();
    let (t, w) = match value.split_once('±').or_else(|| value.split_once("+-")) {
        Some((t, w)) => (t.trim(), w.trim()),
        None => (value, "0"),
    };
    match (t.parse::<f64>(), w.parse::<f64>()) {
        (Ok(t), Ok(w)) if t.is_finite() && w.is_finite() && w >= 0.0 => Ok(Some((t, w))),
        _ => Err(bad()),
    }
}

/// Largest track file read [bytes]: 10⁶ points take about 20 MB.
pub const MAX_TRACK_BYTES: u64 = 256 << 20;

/// A track file's text: a regular file of at most [`MAX_TRACK_BYTES`], its size checked
/// before anything is read.
fn read_text(path: &Path) -> Result<String, String> {
    crate::config::files::capped_file_text(path, MAX_TRACK_BYTES, "a track")
        .map_err(|e| format!("cannot read: {e}"))
}

/// The override of a comment line `# set KEY=VALUE`, if it is one. A key is dotted
/// (`parcel.mass`: letters, digits and `_` between dots); one that is not (`mass`,
/// `parcel.belt-speed`) is an error rather than silently ignored. Other comments (`# set
/// up on 3 May`, `# set the belt = fast`: no `=`, or a key with spaces) are only comments.
fn set_line(comment: &str) -> Result<Option<String>, String> {
    let Some(set) = comment.trim().strip_prefix("set ") else {
        return Ok(None);
    };
    let set = set.trim();
    let Some((key, _)) = set.split_once('=') else {
        return Ok(None);
    };
    let key = key.trim();
    if key.is_empty() || key.contains(char::is_whitespace) {
        return Ok(None);
    }
    let dotted = key.contains('.')
        && key
            .split('.')
            .all(|p| !p.is_empty() && p.chars().all(|c| c.is_ascii_alphanumeric() || c == '_'));
    if dotted {
        Ok(Some(set.to_string()))
    } else {
        Err(
            "`# set KEY=VALUE` needs a dotted key such as parcel.mass or machine.belt_speed \
             (letters, digits and _ between dots)"
                .into(),
        )
    }
}

/// The `# set` overrides of a track file alone (read before its data, so that a track's own
/// camera settings apply to how its data is read).
pub(crate) fn read_sets(path: &Path) -> Result<Vec<String>, String> {
    let text = read_text(path)?;
    let mut sets = Vec::new();
    for (i, line) in text.lines().enumerate() {
        if let Some(c) = line.trim().strip_prefix('#') {
            if let Some(set) = set_line(c).map_err(|e| format!("line {}: {e}", i + 1))? {
                sets.push(set);
            }
        }
    }
    Ok(sets)
}

impl TrackFile {
    /// The track in the machine frame, with the quantisation σ of pixel positions (metre
    /// positions: σ = 0, unknown).
    pub fn to_track(&self, camera: &CameraMap) -> Track {
        let points = self
            .positions
            .iter()
            .map(|p| {
                if self.pixels {
                    camera.to_machine(*p)
                } else {
                    DVec2::from(*p)
                }
            })
            .collect();
        let sigma = self
            .positions
            .iter()
            .map(|p| {
                if self.pixels {
                    camera.quantisation_sigma(*p)
                } else {
                    DVec2::ZERO
                }
            })
            .collect();
        Track {
            times: self.times.clone(),
            points,
            sigma,
        }
    }
}

/// A pixel track as CSV text, with `# set` lines first.
pub fn pixel_csv(sets: &[String], frames: &[(f64, [f64; 2])]) -> String {
    let mut s = String::from("# a marker track written by `divertsim track --synthesize`\n");
    for set in sets {
        s += &format!("# set {set}\n");
    }
    s += "t,u,v\n";
    for (t, p) in frames {
        s += &format!("{t},{},{}\n", p[0], p[1]);
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read_text(text: &str) -> Result<TrackFile, String> {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("t.csv");
        std::fs::write(&p, text).unwrap();
        read(&p, 25.0, [640.0, 480.0], 3.0)
    }

    /// Issue 27 (C13): `# arm_start` pins the alignment, in the time column's unit.
    #[test]
    fn arm_start_lines_are_read_in_the_time_columns_unit() {
        let frames = "0,10,400\n1,12,400\n2,14,399\n3,16,398\n4,20,396\n";
        let rows = "0,10,400\n0.04,12,400\n0.08,14,399\n0.12,16,398\n0.16,20,396\n";
        let t = read_text(&format!("# arm_start = 0.2 ± 0.05\nt,u,v\n{rows}")).unwrap();
        assert_eq!(
            t.arm_start,
            Some(ArmStart {
                time: 0.2,
                within: 0.05
            })
        );
        let t = read_text(&format!("# arm_start = 5 +- 1\nframe,u,v\n{frames}")).unwrap();
        assert_eq!(
            t.arm_start,
            Some(ArmStart {
                time: 0.2,
                within: 0.04
            })
        );
        let t = read_text(&format!("# arm_start=0.3\nt,u,v\n{rows}")).unwrap();
        assert_eq!(t.arm_start.map(|a| (a.time, a.within)), Some((0.3, 0.0)));
        // A comment that only mentions it is a comment.
        let t = read_text(&format!("# arm_start unknown\nt,u,v\n{rows}")).unwrap();
        assert_eq!(t.arm_start, None);
        for bad in ["# arm_start = soon", "# arm_start = 0.2 ± -1"] {
            let e = read_text(&format!("{bad}\nt,u,v\n{rows}")).unwrap_err();
            assert!(e.contains("line 1") && e.contains("arm_start"), "{e}");
        }
        let e = read_text(&format!("# arm_start = 1\n# arm_start = 2\nt,u,v\n{rows}")).unwrap_err();
        assert!(e.contains("twice"), "{e}");
    }

    #[test]
    fn reads_frames_pixels_and_sets() {
        let t = read_text("\u{feff}# set machine.belt_speed=2\n# set up on 3 May\n\"frame\",\"u\",\"v\"\r\n0,10,400\n1,12,400\n2,14,399\n3,16,398\n5,20,396\n").unwrap();
        assert_eq!(t.sets, ["machine.belt_speed=2"]);
        assert!(t.pixels);
        assert_eq!(t.times[4], 0.2);
    }

    #[test]
    fn bad_tracks_name_the_line() {
        let cases = [
            ("t,x,y\n0,0,0\n0.04,0,0\n0.04,0,0\n", "line 4"),
            ("t,u,v\n0,1,1\n0.04,700,1\n", "off the 640×480"),
            ("t,u,v\n0,1,1\n0.04,2,1\n0.4,3,1\n", "gap"),
            ("t,u,v\n0,1,1\n0.04,2,1\n", "at least 5"),
            ("a,b\n1,2\n", "time column"),
            ("t,u,v\n0,1,x\n", "column v"),
        ];
        for (text, want) in cases {
            let e = read_text(text).unwrap_err();
            assert!(e.contains(want), "{text:?}: {e}");
        }
    }

    /// Hostile input round three: `# set mass=2` (no dot) and `# set parcel.belt-speed=2`
    /// (a hyphen) were silently ignored; they are errors naming the line now, while a
    /// comment that only starts with "set" stays a comment.
    #[test]
    fn set_key_without_a_dot_or_with_a_hyphen_is_an_error() {
        let data = "t,x,y\n0,0,0\n0.04,0,0\n0.08,0,0\n0.12,0,0\n0.16,0,0\n";
        for bad in [
            "# set mass=2\n",
            "# set parcel.belt-speed=2\n",
            "# set .mass=2\n",
        ] {
            let e = read_text(&format!("{bad}{data}")).unwrap_err();
            assert!(
                e.contains("line 1") && e.contains("dotted key"),
                "{bad:?}: {e}"
            );
        }
        for fine in [
            "# set up on 3 May\n",
            "# set the belt = fast\n",
            "# setting\n",
        ] {
            let t = read_text(&format!("{fine}{data}")).unwrap();
            assert!(t.sets.is_empty(), "{fine:?}");
        }
    }

    /// Hostile input round three: a track file had no size cap. A sparse file beyond the cap
    /// is refused by its size, before anything is read.
    #[test]
    fn track_larger_than_the_cap_is_refused_before_reading() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("huge.csv");
        let f = std::fs::File::create(&p).unwrap();
        f.set_len(MAX_TRACK_BYTES + 1).unwrap();
        let e = read(&p, 25.0, [640.0, 480.0], 3.0).unwrap_err();
        assert!(e.contains("larger than 256 MiB"), "{e}");
        assert!(read_sets(&p).unwrap_err().contains("larger than"));
    }
}
