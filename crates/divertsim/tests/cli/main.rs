//! End-to-end tests of the `divertsim` binary, one module per command or edge, in one test
//! program: one link of the binary's heavy dependencies instead of one per file.

mod common;

mod calibrate_cli;
mod capacity_cli;
mod capture_cli;
mod check_cli;
mod docs_cli;
mod examples;
mod golden_outputs;
mod invalid_input;
mod line_cli;
mod one_build;
mod optimize_cli;
mod out_promise;
mod output_faults;
mod overload_cli;
mod paths_cli;
mod python_package;
mod reliability_cli;
mod replicate_cli;
mod report_browser;
mod report_tables;
mod scenario_base;
mod scenario_paths;
mod simulate_cli;
mod studio_browser;
mod studio_server;
mod tipping_mix;
mod trigger_cli;
mod worst_case_cli;
