//! The command line: `divertsim simulate`, the analysis commands (one file each under
//! `commands/`), and `schema | example | completions | man`.
//!
//! Exit codes: 0 success (whatever the verdict), 1 an output could not be written,
//! 2 bad input (every problem listed, nothing written), 3 the simulation failed
//! numerically (outputs are still written, with outcome "failed" and its reason), 4 `check`
//! found the setting unsafe (its one verdict that gates).

use clap::{Parser, Subcommand};
use divertsim_api::analyses::capacity::Capacity;
use divertsim_api::analyses::capture::Capture;
use divertsim_api::analyses::check::Check;
use divertsim_api::analyses::line::LineAnalysis;
use divertsim_api::analyses::measurement::{Calibrate, Compare};
use divertsim_api::analyses::optimize::Optimize;
use divertsim_api::analyses::overload::Overload;
use divertsim_api::analyses::reliability::Reliability;
use divertsim_api::analyses::runs;
use divertsim_api::analyses::trigger::TriggerCalibration;
use divertsim_api::analyses::worst_case::WorstCaseSearch;
use divertsim_api::config::{self, Problems};
use divertsim_api::contract::Analysis as _;
use divertsim_api::output;
use divertsim_core::sim::{Outcome, Recording};
use divertsim_figures::plot::{self, PlotOptions};
use std::path::{Path, PathBuf};

/// Simulator of swing-arm parcel diverters: a pivoting arm swings across a belt conveyor
/// and pushes a parcel off. divertsim integrates the parcel's motion through strikes,
/// sliding and contact stages and tells whether it is diverted.
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are --help text: [m] is a unit
#[derive(Debug, Parser)]
#[command(name = "divertsim", version, propagate_version = true)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[allow(rustdoc::broken_intra_doc_links)] // doc comments are --help text: [m] is a unit
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Simulate one parcel on one machine setting.
    #[command(after_help = SIMULATE_EXAMPLES)]
    Simulate(SimulateArgs),
    /// Overlay the centre paths of several scenario files in one top view (paper Figs 6–8).
    #[command(after_help = PATHS_EXAMPLES)]
    Paths(crate::commands::paths::PathsArgs),
    /// `divertsim trigger` ([`TriggerCalibration::ABOUT`]).
    #[command(about = TriggerCalibration::ABOUT, after_help = TRIGGER_EXAMPLES)]
    Trigger(crate::commands::trigger::TriggerArgs),
    /// `divertsim capture` ([`Capture::ABOUT`]).
    #[command(about = Capture::ABOUT, after_help = CAPTURE_EXAMPLES)]
    Capture(crate::commands::capture::CaptureArgs),
    /// `divertsim overload` ([`Overload::ABOUT`]).
    #[command(about = Overload::ABOUT, after_help = OVERLOAD_EXAMPLES)]
    Overload(crate::commands::overload::OverloadArgs),
    /// `divertsim worst-case` ([`WorstCaseSearch::ABOUT`]).
    #[command(about = WorstCaseSearch::ABOUT, after_help = WORST_CASE_EXAMPLES)]
    WorstCase(crate::commands::worst_case::WorstCaseArgs),
    /// `divertsim check` ([`Check::ABOUT`]).
    #[command(about = Check::ABOUT, after_help = CHECK_EXAMPLES)]
    Check(crate::commands::check::CheckArgs),
    /// `divertsim capacity` ([`Capacity::ABOUT`]).
    #[command(about = Capacity::ABOUT, after_help = CAPACITY_EXAMPLES)]
    Capacity(crate::commands::capacity::CapacityArgs),
    /// Rerun the paper's analyses on the paper preset and check its findings (a)–(g):
    /// every figure (SVG, PNG, CSV), findings.md / findings.json and index.html.
    #[command(after_help = REPLICATE_EXAMPLES)]
    Replicate(crate::commands::replicate::ReplicateArgs),
    /// Rerun the runs behind README.md's and docs/validation.md's figures and numbers
    /// (docs/runs.toml) and write them there; --check says what differs instead.
    #[command(after_help = DOCS_EXAMPLES)]
    Docs(crate::commands::docs::DocsArgs),
    /// `divertsim optimize` ([`Optimize::ABOUT`]).
    #[command(about = Optimize::ABOUT, after_help = OPTIMIZE_EXAMPLES)]
    Optimize(crate::commands::optimize::OptimizeArgs),
    /// `divertsim reliability` ([`Reliability::ABOUT`]).
    #[command(about = Reliability::ABOUT, after_help = RELIABILITY_EXAMPLES)]
    Reliability(crate::commands::reliability::ReliabilityArgs),
    /// `divertsim line` ([`LineAnalysis::ABOUT`]).
    #[command(about = LineAnalysis::ABOUT, after_help = LINE_EXAMPLES)]
    Line(crate::commands::line::LineArgs),
    /// Read a filmed marker track (pixels or metres) into the machine frame and check it;
    /// or write the track a camera would record of a simulated run (--synthesize).
    #[command(after_help = TRACK_EXAMPLES)]
    Track(crate::commands::track::TrackCmdArgs),
    /// `divertsim compare` ([`Compare::ABOUT`]).
    #[command(about = Compare::ABOUT, after_help = TRACK_EXAMPLES)]
    Compare(crate::commands::compare::CompareArgs),
    /// `divertsim calibrate` ([`Calibrate::ABOUT`]).
    #[command(about = Calibrate::ABOUT, after_help = TRACK_EXAMPLES)]
    Calibrate(crate::commands::calibrate::CalibrateArgs),
    /// The scenario presets built into divertsim (the repository's configs/): list them,
    /// print one, or write them all into a folder to edit and run.
    #[command(after_help = PRESET_EXAMPLES)]
    Preset(PresetArgs),
    /// A local web page where a setting is tried as fast as a slider moves: the scenario
    /// editor, the animated run redrawn on every change, capacity maps, reliability studies
    /// and line runs with live progress, downloads and share links.
    #[command(after_help = STUDIO_EXAMPLES)]
    Studio(crate::commands::studio::StudioArgs),
    /// Print the JSON Schema of the scenario file (for editors and validators).
    Schema,
    /// Print the built-in default scenario as TOML with every key, each under a comment with
    /// its meaning, unit and range (keys without a default commented out): a starting point
    /// for your own.
    Example,
    /// Print a shell completion script, e.g.
    /// `divertsim completions bash > ~/.local/share/bash-completion/completions/divertsim`.
    Completions {
        /// The shell.
        shell: clap_complete::Shell,
    },
    /// Print the manual page (roff), e.g. `divertsim man > divertsim.1 && man ./divertsim.1`.
    Man,
}

const STUDIO_EXAMPLES: &str = "\
Examples:
  divertsim studio                                # http://127.0.0.1:8740/ (serves until Ctrl-C)
  divertsim studio configs/paper/fig08.toml --open   # a scenario file, opened in the browser (serves until Ctrl-C)

The page is served from the binary and needs no network: the scenario editor (every key
with its unit and range, out-of-range values marked with the CLI's message), the run
redrawn on every change, a capacity map whose cells run their setting when clicked,
reliability studies and line runs with live progress and a cancel, the scenario (TOML), the run's report
and a study's outputs (zip) to download, and the address bar as a share link. It listens on
127.0.0.1 only, unless --host names another address with --allow-remote, and reads no file
beyond the scenario's own (docs/studio.md).";

const PRESET_EXAMPLES: &str = "\
Examples:
  divertsim preset                        # the list, with what each one is
  divertsim preset paper/fig13a           # print one (TOML)
  divertsim preset --write presets        # all of them: presets/paper/*.toml, presets/mix/hub.toml, ...
  divertsim simulate presets/paper/fig13a.toml

An installed divertsim (cargo install) finds the presets here; `replicate` uses them when
there is no configs/paper folder.";

/// Arguments of `divertsim preset`.
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are --help text: [m] is a unit
#[derive(Debug, Clone, clap::Args)]
pub struct PresetArgs {
    /// The preset to print, e.g. paper/fig13a (a path below configs/, .toml optional).
    pub name: Option<String>,
    /// Write every preset below DIR (DIR/paper/machine.toml, ...), all or nothing; DIR must
    /// not exist yet (an empty directory is fine) unless --force; a mount point is refused (give a folder
    /// inside it).
    #[arg(long, value_name = "DIR", conflicts_with = "name")]
    pub write: Option<PathBuf>,
    /// Replace an existing --write DIR whole.
    #[arg(long, requires = "write")]
    pub force: bool,
}

const CHECK_EXAMPLES: &str = "\
Examples:
  divertsim check configs/paper/proposed.toml --out unsafe   # the paper's proposed setting: UNSAFE (exit 4)
  divertsim check configs/paper/robust_optimum.toml          # the robust optimum: SAFE for the paper's parcels
  divertsim check configs/paper/machine.toml                 # reliability's default mix (0.1-0.3 m tall): UNSAFE, one tips over (exit 4)
  divertsim check configs/paper/mix.toml --samples 20000     # with the mix's rates: UNSAFE, the slender parcel stays (exit 4)
  divertsim optimize configs/paper/machine.toml --out opt && divertsim check opt/optimum.toml   # SAFE: optimum.toml states the class it was found for

Checks: divert (the searched smallest divert reserve over [design.search] and each [design]
parcel: a parcel not diverted or tipped over fails), overload (the searched largest
S/S_fall: above 1, the free fall from H0, fails), and the divert, overload and tipping
rates of a mix: the scenario's [mix], else reliability's default (a parcel that tipped over
fails; any other failure there is marginal). The search covers the heights of that mix,
or [design.search] height = [lo, hi] where stated (a mix without heights of its own then
draws them in that band, as in optimize's optimum.toml); --samples 0 skips the mix and
keeps parcel.height.
Verdict: unsafe if a check fails, marginal if a reserve is below --reserve-margin /
--overload-margin or the mix has failures, else safe.
Exit codes: 0 safe or marginal, 4 unsafe, 1 could not write an output, 2 bad input.
With --out DIR: summary.json, scenario.toml and, when unsafe, unsafe_divert.toml /
unsafe_overload.toml / unsafe_tipping.toml (the failing parcel: `divertsim simulate
DIR/unsafe_overload.toml`).";

const OPTIMIZE_EXAMPLES: &str = "\
Examples:
  divertsim optimize configs/paper/machine.toml --method de --out opt     # DE + COBYLA polish
  divertsim optimize configs/paper/machine.toml --method ga --worst paper --seed 2 --bound v=1.5:2.3 --bound R_s=0:0.5
  divertsim optimize configs/paper/machine.toml --method gradient --worst paper --start 1.8,1.5,0.5   # the paper's methods
  divertsim optimize configs/paper/machine.toml --method nsga2 --out front  # front.csv, front.svg
  divertsim optimize configs/paper/machine.toml --paper-experiment --out paper --threads 2
  divertsim optimize configs/paper/machine.toml --compare --seeds 5 --out methods

  divertsim optimize configs/paper/machine.toml --margin overload=0.1,divert=0.02 --scatter phase=0.01
  divertsim optimize configs/paper/machine.toml --worst paper          # the paper's closed-form worst case

  divertsim optimize configs/paper/line.toml --objective line --out optline # the line's parcels/h
  divertsim optimize configs/paper/line.toml --objective line --max-missort 0.005 --parcels 1000  # a looser limit

Variables: belt_speed|v, cycle_time|t_c, start_position|R_s, light_barrier|S_d; defaults
v 1.0:2.3 m/s, t_c 1.0:1.5 s, R_s 0:0.9 m, S_d fixed at the scenario's light_barrier
(--bound NAME=LO:HI, --fix NAME=VALUE, or in the scenario file: [optimize] belt_speed = [1.5, 2.3],
light_barrier = 0.0, ...; the command line overrides the file). Constraints g <= 0: every [design] parcel diverted
(g = margin - divert overshoot [m]), overload S/S_fall - (1 - margin), S_d - R_s.
With --worst search (the default) the overload is the largest simulated S/S_fall, and the
setting must also hold for every parcel of [design.search] in any pose and arrival: rounds of
optimisation against a set of worst poses and a worst-case search at the optimum, which adds
the poses that violate, until the search finds none (--rounds; --search-budget per search).
Outputs with --out DIR: evaluations.csv (every candidate of the last round), history.csv,
history.svg, summary.json (with the rounds and the worst poses) (nsga2: front.csv, front.svg),
optimum.toml (the scenario at the best point: `divertsim simulate opt/optimum.toml` runs it).
With --objective line the objective is the throughput of the scenario's [line] (parcels/h
correctly diverted) over --parcels parcels, the same parcels at every point (common random
numbers); the constraints are the missort rate <= --max-missort, the overload rate <=
--max-overload and S_d - R_s <= 0; `divertsim line opt/optimum.toml --parcels N --seed S`
gives the best point's figures.";

const TRACK_EXAMPLES: &str = "\
Examples:
  divertsim track configs/paper/fig13a.toml --synthesize fig13a.csv     # a synthetic pixel track
  divertsim track configs/paper/fig13b.toml --synthesize fig13b.csv     # two more runs, filmed
  divertsim track configs/paper/fig15b.toml --synthesize fig15b.csv
  divertsim track configs/paper/machine.toml --track fig13a.csv --out m # check it, in metres
  divertsim compare configs/paper/machine.toml --track fig13a.csv --track fig15b.csv --out cmp
  divertsim calibrate configs/paper/machine.toml --track fig13a.csv --track fig13b.csv \\
      --track fig15b.csv --fit materials.belt_friction,materials.arm_friction,materials.restitution --out cal
  divertsim simulate cal/calibrated.toml --set parcel.length=0.7 --set parcel.width=0.1

A track is CSV with a header: t [s] (or frame, with camera.frame_rate), then u, v [px] or
x, y [m] of a marker on the parcel. Comment lines `# set KEY=VALUE` give the experiment's
own settings (parcel, belt speed, R_s) over the scenario given; --synthesize writes them.
The [camera] section maps pixels to the machine frame: px_per_m, origin_px, x_axis_px,
y_axis_px for a camera square to the belt (default: the paper's 304 px per 0.6 m,
640 x 480, 25 fps), or four reference_points [u, v, x, y] for an oblique one; and
marker_offset, the marker's place on the parcel [m]. Video and simulation clocks are
aligned per track by fitting the time of the arm start.
calibrate: a global search (differential evolution, then a compass search) and a robust
Levenberg-Marquardt on a Huber loss (--huber); each value gets a 95 % profile-likelihood
interval, and a value the tracks cannot pin down is reported NOT IDENTIFIABLE.
Outputs with --out DIR: summary.json, calibrated.toml, profiles.csv, fit_<track>.svg/.png,
report.html (the runs animated with the measured points) (compare: comparison.csv,
summary.json, compare_<track>.svg/.png, report.html).";

const LINE_EXAMPLES: &str = "\
Examples:
  divertsim line                                          # 10 000 parcels, one diverter, 2.5 m gaps ± 16 %
  divertsim line configs/paper/line_two.toml --out line2     # line_parcels.parquet, failures/
  divertsim line configs/paper/line.toml --sweep line.gap_target=0.25:4/16 --out gaps   # the throughput curve
  divertsim line --parcels 100000 --out big --resume        # after a kill: the same bytes

The [line] section says what the line is ([machine] is the first diverter, at 0):
  [line]
  share = 0.5                                  # parcels bound for the first diverter
  gap_target = 1.5                             # clear gap, rear to front [m]
  gap_scatter = 0.16                           # its scatter (sd / target), or gap = {kind = ...}
  min_gap = 0.1                                # the induction's smallest gap [m]
  busy_rule = \"skip\"                           # or \"late\" (within max_delay), \"barrier\" (the paper's W)
  [[line.diverters]]                           # further diverters, down the belt
  position = 4.0                               # its pivot, from the first's [m]
  share = 0.5
  machine = { cycle_time = 1.2 }               # where its machine differs from [machine]

Each parcel is run against every stroke of the arm near it; a parcel no stroke can reach
costs no simulation. Outcomes: diverted, passed, arm_busy (the arm was still in a cycle),
not_diverted (with the physical reason), struck_in_passing, wrongly_diverted, collision
(footprints overlapped: detected, not resolved), failed. Throughput is parcels per hour
diverted into their own chute; the paper's W assumes one parcel per cycle.";

const RELIABILITY_EXAMPLES: &str = "\
Examples:
  divertsim reliability                                   # 10 000 parcels of the default mix
  divertsim reliability configs/mix/hub.toml --samples 100000 --out sample   # samples.parquet, plots
  divertsim reliability configs/mix/hub.toml --until-ci 0.002 --json
  divertsim reliability configs/mix/hub.toml --sweep machine.belt_speed=1.5:2.3/9 --out speeds
  divertsim reliability configs/mix/hub.toml --sweep machine.trigger=fixed,adaptive
  divertsim reliability configs/mix/hub.toml --samples 1000000 --out hub --resume  # kill it, rerun: it continues
  divertsim reliability configs/mix/hub.toml --samples 20000 --out loads  # load_spectrum.csv, largest_stroke.toml
  divertsim simulate loads/largest_stroke.toml          # the stroke with the largest peak drive torque, again

The [mix] section gives each quantity as a distribution (SI; angles in degrees):
  [mix]
  length = { kind = \"lognormal\", median = 0.35, sigma = 0.35 }     # the longer side [m]
  width = { kind = \"uniform\", min = 0.1, max = 0.3 }               # sorted: width <= length
  height = { kind = \"fixed\", value = 0.15 }
  density = { kind = \"normal\", mean = 150, sd = 40 }               # or mass = ... [kg]
  offset_fraction = { kind = \"uniform\", min = 0, max = 1 }         # or offset = ... [m]
  angle_deg = { kind = \"truncated-normal\", mean = 0, sd = 10, min = -30, max = 30 }
  phase = { kind = \"normal\", mean = 0, sd = 0.005 }                # trigger error [s]
  arm_friction = { kind = \"discrete\", values = [0.3, 0.4], weights = [3, 1] }
  # also speed (arrival, relative to the belt), spin, belt_friction, restitution,
  # records = \"log.csv\" (columns length,width,height[,mass]), seed
Kinds: fixed, uniform, normal, truncated-normal, lognormal (median, sigma of ln x), discrete.
Draws that do not fit on the belt or leave the model's ranges are redrawn and counted.
machine.trigger = \"adaptive\" starts the arm at each parcel's own R_s from a table over its
length, aspect, offset and angle ([machine.adaptive]); R_s never upstream of S_d.

A failure is a parcel not diverted (or a failed run); an overload a strike above the free
fall from limits.drop_height. Intervals: 95 % Clopper-Pearson. Sample i depends only on
(seed, i): results are identical for any --threads, and a run killed at any moment resumes
with --resume to the byte-identical result. Outputs with --out DIR: summary.json,
samples.parquet (samples.csv with --csv), failure_rates.csv, failure_rate.svg/.png,
divert_reserve.svg/.png, overload_ratio.svg/.png (sweep.svg/.png with --sweep),
load_spectrum.csv and .svg/.png (each stroke's peak drive torque and each strike's angular
impulse on the arm, counts per 10^6 strokes) and largest_stroke.toml (the stroke with the
largest peak, for simulate).";

const CAPACITY_EXAMPLES: &str = "\
Examples:
  divertsim capacity --worst paper                     # 20 x 20 map, the built-in machine, in seconds
  divertsim capacity configs/paper/machine.toml --out cap   # capacity.csv, capacity.svg; robust: ~15 s on 2 cores
  divertsim capacity --cycle-times 1.2:1.4/3 --light-barriers 0:0.4/3 --speeds 1.5:2.1/4 --json

  divertsim capacity configs/paper/machine.toml --worst paper   # the paper's algorithm as published
  divertsim capacity --worst paper --margin drive_torque=40     # and every run's peak drive torque <= 40 N*m

For each (t_c, v) the R_s that divert every [design] parcel are found on an R_s grid
(--start-range, --start-step) refined by bisection (--start-tolerance);
W = 3600/((R_s - S_d)/v + t_c) is maximised over v and R_s >= S_d. With --worst paper,
settings whose closed-form worst-case overload exceeds the free fall from
limits.drop_height are discarded. With --worst search (the default) every run's simulated
overload counts, and at each feasible cell's chosen setting a worst-case search over
[design.search] looks for a parcel that is struck too hard or not diverted; such poses join
the checks and the map is recomputed until none is found (--rounds). Slower: minutes for the
20 x 20 map.";

const DOCS_EXAMPLES: &str = "\
Examples (from the repository root):
  divertsim docs --check --only replicate   # is docs/figures what a fresh `replicate` gives?
  divertsim docs --only line_two            # rerun one run, write its figures and numbers

Without --only, every run of docs/runs.toml (about 20 minutes on 2 cores; the test
suite runs `divertsim docs --check` so). docs/runs.toml lists the runs: a divertsim command
line each, and the figures of its output that the documents show. A number in README.md or
docs/validation.md sits between markers naming its run and its place in the run's
summary.json (CSV tables of its output under their file names):
  <!--n mix_documentation /points/0/failure_rate/estimate pct:2-->9.27<!--/n--> %
(a JSON pointer; `*` takes the largest over an array, `#` its length, `A|B` a ratio, a
final `?` reads 0 where nothing is; formats pct:N, fix:N, int, text; a value the run has
as none at a plain pointer, a null or an empty CSV cell, is written —). The prose around a
number is not rewritten: read it after a run that changed one. Exit 1 with --check when
something differs, 2 on bad input or a failed run.
";

const REPLICATE_EXAMPLES: &str = "\
Examples (from the repository root):
  divertsim replicate --out docs/figures     # the report's figures, under half a minute on 2 cores
  divertsim replicate --quick --out /tmp/r   # coarse grids, a smoke run in seconds
  divertsim replicate --configs my/preset --out my/figures --json

Reads machine.toml, fig03, fig05-fig08, fig13a/b, fig14a/b, fig15a/b from --configs and writes
findings_abc, fig03/13/14/15, trigger, capture, overload and capacity (.svg, .png, .csv),
findings.md, findings.json and index.html (every finding with its figure, (a)-(c) animated).
Each finding's verdict is computed from the numbers.";

const WORST_CASE_EXAMPLES: &str = "\
Examples:
  divertsim worst-case configs/paper/machine.toml --set machine.belt_speed=2 --set machine.start_position=0
  divertsim worst-case --out wc          # worst_impulse.toml, worst_reserve.toml (+ .svg, _trajectory.csv)
  divertsim worst-case --scatter belt_speed=0.02,phase=0.01 --search-budget 10000 --json
  divertsim worst-case --torque --set machine.arm_mass=8 --out wct   # + worst_torque.toml: the largest drive torque

The setting is the scenario's machine (v, t_c, R_s). The search varies what nobody controls,
within [design.search] (default: the paper's class 0.2-0.7 x 0.1-0.26 m, 0.5-15 kg, +-30 deg,
anywhere across the belt, +-10 ms trigger phase): several differential-evolution starts, then
a compass search. `divertsim simulate worst_impulse.toml` reproduces the worst run exactly.";

const OVERLOAD_EXAMPLES: &str = "\
Examples:
  divertsim overload                                   # t_c of the scenario, v 0.5..2.5 m/s
  divertsim overload --set machine.cycle_time=1.2 --speeds 0.5:2.5/9 --out ov
  divertsim overload --drop-heights 0.2,0.3,0.5 --worst paper --json   # closed form only
  divertsim overload configs/paper/machine.toml --worst paper --out ovl   # paper Fig. 16

At each speed the worst case is searched by simulation (the default --worst search, as for
capacity, optimize and check): any parcel of [design.search] in any pose and arrival, at
any R_s of --start-range. Beside it the paper's worst case is always shown: the
[design.overload] parcel (default 0.4x0.26 m, 15 kg) riding at v, struck at its front
pivot-side corner by the arm tip at the largest arm angular velocity of the drive. Ordinary
parcels can beat the paper's case; --worst paper gives it alone, in closed form.";

const SIMULATE_EXAMPLES: &str = "\
Examples:
  divertsim simulate                                   # the built-in default scenario
  divertsim simulate configs/default.toml --out run1   # trajectory.csv, summary.json, plot.svg/.png, report.html
  divertsim simulate configs/paper/fig08.toml --report fig08.html   # the animated report alone
  divertsim simulate --set machine.belt_speed=1.5 --set parcel.angle_deg=10 --plot top.png
  divertsim simulate --json --set run.arm=false --set parcel.velocity=[3.0,0.0]

Keys (see `divertsim example` for all of them, `divertsim schema` for their documentation):
  machine.{belt_width, belt_speed, arm_length, cycle_time, start_position, light_barrier,
           near_side, trigger}    machine.adaptive.{length_nodes, ..., search, step}
  machine.drive.{kind, max_swing_deg, crank, coupler, rocker, ground, table, points}
  parcel.{length, width, height, mass, offset, angle_deg, velocity, spin}
  materials.{belt_friction, arm_friction, restitution, friction_model, impact_law}
  run.{duration, tolerance, arm}    limits.{drop_height}
  [mix] (divertsim reliability --help), [camera] (divertsim track --help), [design], [optimize]
SI units; angles in degrees in keys ending in _deg.

Exit codes: 0 ran (any verdict), 1 could not write an output, 2 bad input, 3 numerical failure.";

const PATHS_EXAMPLES: &str = "\
Examples:
  divertsim paths configs/paper/fig06.toml configs/paper/fig07.toml configs/paper/fig08.toml --out figs
  divertsim paths configs/paper/fig13a.toml configs/paper/fig13b.toml --label 'v = 0.65 m/s' --label 'v = 2 m/s' --plot fig13.svg
  divertsim paths configs/paper/fig06.toml configs/paper/fig14a.toml --set materials.belt_friction=0.4 --json

Writes paths.svg and paths.csv (case, t, x, y, phi_deg, stage) into --out DIR; --set applies to every file.
Exit codes: 0 ran (any verdict), 1 could not write an output, 2 bad input, 3 a case failed numerically.";
const TRIGGER_EXAMPLES: &str = "\
Examples:
  divertsim trigger configs/paper/fig06.toml --out trig    # the paper's Fig. 4: slender parcel
                                                          # at ΔP = 0, v = 0.65..2.3 m/s
  divertsim trigger --speeds 1.0,1.5,2.0 --json            # no file: the same Fig. 3 parcel
  divertsim trigger --reference-start 0.6 --search 0:1 --tolerance 1e-3

For each speed, R_s is scanned over --search every --scan-step and every sign change of
max_lateral(R_s) - target is refined by bisection; with several roots the one continuing the
curve from the reference is chosen. Without a scenario file the parcel is the paper's Fig. 3
case (0.7 x 0.1 x 0.1 m, 1.5 kg, ΔP = 0, φ = 0) on the paper preset's machine
(configs/paper/machine.toml). The reference run must not be diverted.
Outputs with --out DIR: trigger.csv, trigger.svg.";

const CAPTURE_EXAMPLES: &str = "\
Examples:
  divertsim capture --speeds 1.0,1.5,2.0 --trigger --out cap  # the paper's Fig. 5 case
  divertsim capture --set parcel.offset=0.0 --set parcel.length=0.7 --json
  divertsim capture configs/paper/fig08.toml --speeds 2.0

Without a scenario file the parcel is the paper's Fig. 5 case: the smallest parcel
0.2 x 0.1 x 0.1 m (0.5 kg) farthest from the pivot (ΔP = 0.6 m), t_c = 1.36 s, on the paper
preset's machine (configs/paper/machine.toml). Captured: the
arm line meets the front corner within reach (above α_z = asin(y_c/R_z)). The full simulation
of the same case is reported beside it (first arm strike, outcome).
Outputs with --out DIR: capture.csv (curves), capture.svg.";

#[allow(rustdoc::broken_intra_doc_links)] // doc comments are --help text: [m] is a unit
#[derive(Debug, clap::Args)]
pub struct SimulateArgs {
    /// Scenario file (TOML), or `-` to read it from standard input. Without it, the
    /// built-in default: the paper's compact parcel 0.4×0.26×0.15 m at ΔP = 0.22 m,
    /// v = 2 m/s, t_c = 1.36 s, R_s = 0.
    pub scenario: Option<PathBuf>,
    /// Override a key by dotted path with a TOML value, e.g. machine.belt_speed=1.5 or
    /// parcel.velocity=[3.0,0.0]. Repeatable; validated like the file. A file path given
    /// here (machine.drive.table, mix.records, line.arrivals) is relative to the working
    /// directory.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub sets: Vec<String>,
    /// Let the scenario read files outside its own directory: an absolute path, one with a
    /// `..` component or a symbolic link leading out, in base, machine.drive.table,
    /// mix.records or line.arrivals (in a --set, outside the working directory). Without it
    /// they are refused, so that a scenario file from elsewhere reads only the files beside it
    /// or below it. Files divertsim writes need it only for mix.records and line.arrivals,
    /// which they keep as absolute paths.
    #[arg(long)]
    pub allow_outside_paths: bool,
    /// Write trajectory.csv, summary.json, scenario.toml, report.html and the top view
    /// (plot.svg, plot.png) into DIR, all or nothing. DIR must not exist yet (an empty
    /// directory is fine) unless --force; a mount point is refused (give a folder inside it).
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Replace an existing --out DIR whole.
    #[arg(long, requires = "out")]
    pub force: bool,
    /// Print the summary as one JSON object on stdout instead of the readable text.
    #[arg(long)]
    pub json: bool,
    /// Draw the top view into FILE (.svg or .png).
    #[arg(long, value_name = "FILE")]
    pub plot: Option<PathBuf>,
    /// Write the HTML report into FILE (.html): the animated top view, linked plots and the
    /// summary, one self-contained file that opens offline.
    #[arg(long, value_name = "FILE")]
    pub report: Option<PathBuf>,
    /// Accepted as in every command: one run shows no progress, so it changes nothing.
    #[arg(short, long)]
    pub quiet: bool,
}

/// Run the command line; returns the process exit code.
pub fn run(cli: Cli) -> i32 {
    match cli.command {
        Command::Schema => {
            crate::commands::common::emit_json(&config::json_schema());
            0
        }
        Command::Example => {
            emit(&config::example::example_toml());
            0
        }
        Command::Completions { shell } => {
            use clap::CommandFactory;
            let mut out = Vec::new();
            clap_complete::generate(shell, &mut Cli::command(), "divertsim", &mut out);
            emit(&String::from_utf8_lossy(&out));
            0
        }
        Command::Man => {
            use clap::CommandFactory;
            let mut out = Vec::new();
            match clap_mangen::Man::new(Cli::command()).render(&mut out) {
                Ok(()) => {
                    emit(&String::from_utf8_lossy(&out));
                    0
                }
                Err(e) => {
                    eprintln!("error: cannot render the manual page: {e}");
                    1
                }
            }
        }
        Command::Preset(args) => preset_cmd(&args),
        Command::Simulate(args) => simulate_cmd(&args),
        Command::Paths(args) => crate::commands::paths::run(&args),
        Command::Trigger(args) => crate::commands::trigger::run(&args),
        Command::Capture(args) => crate::commands::capture::run(&args),
        Command::Capacity(args) => crate::commands::capacity::run(&args),
        Command::Overload(args) => crate::commands::overload::run(&args),
        Command::WorstCase(args) => crate::commands::worst_case::run(&args),
        Command::Check(args) => crate::commands::check::run(&args),
        Command::Replicate(args) => crate::commands::replicate::run(&args),
        Command::Docs(args) => crate::commands::docs::run(&args),
        Command::Optimize(args) => crate::commands::optimize::run(&args),
        Command::Reliability(args) => crate::commands::reliability::run(&args),
        Command::Line(args) => crate::commands::line::run(&args),
        Command::Track(args) => crate::commands::track::run(&args),
        Command::Compare(args) => crate::commands::compare::run(&args),
        Command::Calibrate(args) => crate::commands::calibrate::run(&args),
        Command::Studio(args) => crate::commands::studio::run(&args),
    }
}

use crate::commands::common::emit;

fn plot_extension_ok(path: &Path) -> bool {
    matches!(
        path.extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .as_deref(),
        Some("svg") | Some("png")
    )
}

fn preset_cmd(args: &PresetArgs) -> i32 {
    use divertsim_api::presets;
    if let Some(dir) = &args.write {
        let problems = crate::commands::common::claim_problems(dir, args.force);
        if let Err(code) = crate::commands::common::check(problems) {
            return code;
        }
        return match crate::outdir::publish(dir, &[], &mut |staging| {
            presets::write_all(staging).map_err(|e| e.to_string())
        }) {
            Ok(()) => {
                eprintln!(
                    "wrote {} presets below {}",
                    presets::PRESETS.len(),
                    dir.display()
                );
                0
            }
            Err(e) => {
                eprintln!("error: {e}");
                1
            }
        };
    }
    match &args.name {
        None => {
            let mut text = String::from("Built-in presets (divertsim preset NAME prints one):\n");
            for (path, body) in presets::PRESETS {
                let name = path.trim_end_matches(".toml");
                text += &format!("  {name:<14} {}\n", presets::description(body));
            }
            emit(&text);
            0
        }
        Some(name) => match presets::find(name) {
            Some((_, body)) => {
                emit(body);
                0
            }
            None => {
                let names: Vec<&str> = presets::PRESETS
                    .iter()
                    .map(|(p, _)| p.trim_end_matches(".toml"))
                    .collect();
                eprint!(
                    "error: {}",
                    Problems(vec![config::Problem::new(
                        "NAME",
                        format!("no preset '{name}'; allowed: {}", names.join(", "))
                    )])
                );
                2
            }
        },
    }
}

fn simulate_cmd(args: &SimulateArgs) -> i32 {
    let options = config::LoadOptions {
        allow_outside_paths: args.allow_outside_paths,
        ..Default::default()
    };
    let loaded = config::load_with(args.scenario.as_deref(), &args.sets, options);
    let mut problems = match &loaded {
        Ok(_) => Problems(Vec::new()),
        Err(p) => p.clone(),
    };
    add_cli_problems(args, &mut problems);
    match loaded {
        Ok(loaded) if problems.0.is_empty() => simulate_loaded(args, loaded),
        _ => {
            eprint!("error: {problems}");
            2
        }
    }
}

fn add_cli_problems(args: &SimulateArgs, problems: &mut Problems) {
    if let Some(p) = &args.plot {
        if !plot_extension_ok(p) {
            problems.0.push(config::Problem::new(
                "--plot",
                format!("{}: the extension must be .svg or .png", p.display()),
            ));
        }
    }
    if let Some(r) = &args.report {
        let html = r
            .extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| e.eq_ignore_ascii_case("html") || e.eq_ignore_ascii_case("htm"));
        if !html {
            problems.0.push(config::Problem::new(
                "--report",
                format!("{}: the extension must be .html", r.display()),
            ));
        }
    }
    if let Some(d) = &args.out {
        problems
            .0
            .extend(crate::commands::common::claim_problems(d, args.force));
    }
}

fn simulate_loaded(args: &SimulateArgs, loaded: config::Loaded) -> i32 {
    let resolved = config::to_toml(
        &loaded.file,
        "The scenario of this run, every input resolved.",
    )
    .unwrap_or_default();
    // The per-parcel trigger (an adaptive one: this parcel's own best R_s), the run and its
    // summary, exactly as the Python package's `simulate` does them.
    let run = runs::run(&loaded, Recording::Full);
    let summary = runs::summary(&run, &loaded.file);
    let runs::Run {
        scenario,
        result,
        trigger: adaptive,
    } = run;

    if let Some(dir) = &args.out {
        let csv = match output::trajectory_csv(&scenario, &result) {
            Ok(c) => c,
            Err(e) => {
                eprintln!("error: cannot format the trajectory: {e}");
                return 1;
            }
        };
        let json = serde_json::to_vec_pretty(&summary).unwrap_or_default();
        let files = vec![
            ("trajectory.csv".to_string(), csv),
            ("summary.json".to_string(), json),
            ("scenario.toml".to_string(), resolved.clone().into_bytes()),
            (
                "report.html".to_string(),
                divertsim_report::run::single(&scenario, &result, &resolved).into_bytes(),
            ),
        ];
        let mut render = |staging: &Path| {
            for name in ["plot.svg", "plot.png"] {
                plot::top_view(
                    &scenario,
                    &result,
                    &staging.join(name),
                    &PlotOptions::default(),
                )
                .map_err(|e| e.to_string())?;
            }
            Ok(())
        };
        if let Err(e) = crate::outdir::publish(dir, &files, &mut render) {
            eprintln!("error: {e}");
            return 1;
        }
    }
    if let Some(path) = &args.plot {
        let written = crate::outdir::write_file(path, &mut |tmp| {
            plot::top_view(&scenario, &result, tmp, &PlotOptions::default())
                .map_err(|e| e.to_string())
        });
        if let Err(e) = written {
            eprintln!("error: cannot write the plot {}: {e}", path.display());
            return 1;
        }
    }
    if let Some(path) = &args.report {
        let html = divertsim_report::run::single(&scenario, &result, &resolved);
        let written = crate::outdir::write_file(path, &mut |tmp| {
            std::fs::write(tmp, &html).map_err(|e| e.to_string())
        });
        if let Err(e) = written {
            eprintln!("error: cannot write the report {}: {e}", path.display());
            return 1;
        }
    }
    if args.json {
        crate::commands::common::emit_json(&summary);
    } else {
        if let Some(best) = &adaptive {
            emit(&format!(
                "adaptive trigger: R_s = {:.4} m, the middle of the R_s that divert within the limits, [{:.4}, {:.4}] m{} ({} runs)\n",
                scenario.machine.start_position,
                best.interval.0,
                best.interval.1,
                if best.feasible { "" } else { " (none passes: the nearest)" },
                best.simulations
            ));
        }
        emit(&output::summary_text(&scenario, &result));
    }
    match result.outcome {
        Outcome::Failed(_) => 3,
        _ => 0,
    }
}
