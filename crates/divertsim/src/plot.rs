//! Top-view plot (placeholder until the plot module lands).
use divertsim_core::model::params::Scenario;
use divertsim_core::sim::SimResult;
use std::path::Path;

pub struct PlotOptions {
    pub outlines: usize,
    pub arm_positions: usize,
    pub title: Option<String>,
    pub width: u32,
    pub height: u32,
}
impl Default for PlotOptions {
    fn default() -> Self {
        PlotOptions { outlines: 8, arm_positions: 6, title: None, width: 1000, height: 700 }
    }
}
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    #[error("unknown extension {0}")]
    UnknownExtension(String),
}
pub fn top_view(_: &Scenario, _: &SimResult, path: &Path, _: &PlotOptions) -> Result<(), PlotError> {
    std::fs::write(path, b"").ok();
    Ok(())
}
