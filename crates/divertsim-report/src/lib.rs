//! # divertsim-report (the HTML pages and the documents' numbers)
//!
//! Self-contained HTML pages built from the library API's results and the figures' colours,
//! for every edge: the command line writes them into its output folders, the studio serves
//! them, Python returns them (`Result.report`). No files are read or written here: a page is
//! text, and a set of linked pages is [`Pages`], each with the path it expects beside the
//! others.
//!
//! - [`run`]: one run, or several side by side, animated, with linked plots;
//! - [`study`]: a reliability study's rates, loads, plots and its failed samples' runs;
//! - [`line`](mod@line): a sorter line's rates, its animated stream and its failures' runs;
//! - [`paper`]: the charts of the paper's analyses and `replicate`'s index page;
//! - [`assets`]: the scripts and styles the studio serves to show the same viewer;
//! - [`markers`]: the documentation's numbers, each marked with the run, the value and the
//!   format it is written from, filled from the runs' summaries.

pub mod line;
pub mod markers;
pub mod paper;
pub mod run;
pub mod study;

/// Linked pages: each a path relative to the folder they go in (`report.html`,
/// `runs/sample_0_3.html`, ...) and its HTML, the main page last.
pub type Pages = Vec<(String, String)>;

/// The viewer's scripts and styles, for an edge that serves them as files (the studio).
pub mod assets {
    /// The run viewer's script.
    pub const REPORT_JS: &str = include_str!("../assets/report/report.js");
    /// The run viewer's styles.
    pub const REPORT_CSS: &str = include_str!("../assets/report/report.css");
    /// uPlot's script (MIT, assets/uplot/LICENSE).
    pub const UPLOT_JS: &str = include_str!("../assets/uplot/uPlot.iife.min.js");
    /// uPlot's styles.
    pub const UPLOT_CSS: &str = include_str!("../assets/uplot/uPlot.min.css");
}
