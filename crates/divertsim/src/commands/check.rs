//! `divertsim check`: one verdict on a setting, safe, marginal or unsafe, on the api's
//! contract ([`divertsim_api::analyses::check::Check`]). This edge writes the failing
//! parcels' scenario files with `--out` and turns an unsafe verdict into exit code 4, so
//! that a script or a design review can gate on it.

use std::path::Path;

use divertsim_api::analyses::check::{failing_tomls, Check, CheckReport, Verdict};
use divertsim_api::config::Loaded;

use super::analysis::{self, View};
use super::common::{OutputArgs, ScenarioArgs};
use crate::flags::OptionArgs;
use divertsim_core::run::memo::Memo;

/// The exit code of an unsafe setting.
pub const UNSAFE: i32 = 4;

/// Judge a setting against its parcel class.
#[derive(Debug, Clone, clap::Args)]
pub struct CheckArgs {
    #[command(flatten)]
    pub scenario: ScenarioArgs,
    #[command(flatten)]
    pub options: OptionArgs<Check>,
    #[command(flatten)]
    pub output: OutputArgs,
}

/// The failing parcels' scenario files, into the staging folder of `--out`.
fn files(r: &CheckReport, loaded: &Loaded, staging: &Path, _: &dyn Memo) -> Result<(), String> {
    for (name, text) in failing_tomls(r, loaded).map_err(|e| e.to_string())? {
        std::fs::write(staging.join(&name), text).map_err(|e| format!("{name}: {e}"))?;
    }
    Ok(())
}

/// `divertsim check`.
pub fn run(args: &CheckArgs) -> i32 {
    let mut view = View::files(&files);
    view.exit = Some(&|r: &CheckReport| match r.verdict {
        Verdict::Unsafe => UNSAFE,
        _ => 0,
    });
    analysis::run::<Check>(&args.scenario, None, &args.output, &args.options, view)
}
