//! `divertsim studio`: start the local web page of [`crate::studio`] and print its address.

use crate::studio::{self, Studio, StudioOptions};
use std::net::IpAddr;
use std::path::PathBuf;

/// The port the studio tries first; if it is taken, any free port (said on start).
pub const DEFAULT_PORT: u16 = 8740;

/// Arguments of `divertsim studio`.
#[allow(rustdoc::broken_intra_doc_links)] // doc comments are --help text
#[derive(Debug, clap::Args)]
pub struct StudioArgs {
    /// The scenario file the page starts from (TOML; default: the built-in default scenario).
    /// Files it names (base, a drive table, mix records) are read as `simulate` reads them.
    pub scenario: Option<PathBuf>,
    /// The port to listen on; 0 picks any free port. Default 8740, or any free port when
    /// 8740 is taken.
    #[arg(long)]
    pub port: Option<u16>,
    /// The address to listen on. Default 127.0.0.1 (this machine only). Any other address
    /// serves everyone who can reach it and needs --allow-remote.
    #[arg(long, default_value = "127.0.0.1")]
    pub host: IpAddr,
    /// Allow a --host other than loopback (a team server): anyone who reaches the address can
    /// run simulations and studies on this machine, and every client sees, and can cancel,
    /// every study (studies are not scoped to clients; the page has no login).
    #[arg(long)]
    pub allow_remote: bool,
    /// Open the page in the default browser once it is served.
    #[arg(long)]
    pub open: bool,
    /// Studies (capacity maps, reliability studies, line runs) that may run at once, 1 to 16.
    #[arg(long, default_value_t = 2, value_parser = clap::value_parser!(u64).range(1..=16))]
    pub max_studies: u64,
    /// Worker threads of each study, 1 to 1024 (default: every core but one, so that the
    /// live runs stay quick while a study runs).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..=1024))]
    pub study_threads: Option<u64>,
    /// Allow the scenario file to name files outside its own folder.
    #[arg(long)]
    pub allow_outside_paths: bool,
}

/// `divertsim studio`.
pub fn run(args: &StudioArgs) -> i32 {
    if !args.host.is_loopback() && !args.allow_remote {
        eprint!(
            "error: {}",
            divertsim_api::config::Problems(vec![divertsim_api::config::Problem::new(
                "--host",
                format!(
                    "{} is not a loopback address: the studio would serve anyone who reaches it; add --allow-remote to mean it",
                    args.host
                ),
            )])
        );
        return 2;
    }
    let cores = std::thread::available_parallelism().map_or(2, |n| n.get());
    let options = StudioOptions {
        scenario: args.scenario.clone(),
        allow_outside_paths: args.allow_outside_paths,
        host: args.host,
        port: args.port.unwrap_or(DEFAULT_PORT),
        max_studies: args.max_studies as usize,
        study_threads: args
            .study_threads
            .map_or((cores - 1).max(1), |n| n as usize),
    };
    let studio = match Studio::new(&options) {
        Ok(s) => s,
        Err(problems) => {
            eprint!("error: {problems}");
            return 2;
        }
    };
    if !args.host.is_loopback() {
        eprintln!(
            "warning: serving on {} (--allow-remote): anyone who reaches this address can run simulations here, and see and cancel every study; the page has no login",
            args.host
        );
    }
    let open = args.open;
    let ready = move |addr: std::net::SocketAddr| {
        let url = format!("http://{addr}/");
        // The first line of standard output is the address (scripts read it).
        println!("divertsim studio: {url}");
        eprintln!("serving {url} (Ctrl-C stops it)");
        if open {
            open_browser(&url);
        }
    };
    // The default port taken by another program: any free port instead.
    let mut served = studio::serve_on(&options, studio, ready);
    if let Err(studio::ServeError::Bind(e, studio)) = served {
        if args.port.is_none() && e.kind() == std::io::ErrorKind::AddrInUse {
            eprintln!("port {DEFAULT_PORT} is in use; serving on another free port");
            let any = StudioOptions {
                port: 0,
                ..options.clone()
            };
            served = studio::serve_on(&any, *studio, move |addr| {
                let url = format!("http://{addr}/");
                println!("divertsim studio: {url}");
                eprintln!("serving {url} (Ctrl-C stops it)");
                if open {
                    open_browser(&url);
                }
            });
        } else {
            served = Err(studio::ServeError::Bind(e, studio));
        }
    }
    match served {
        Ok(()) => 0,
        Err(studio::ServeError::Bind(e, _)) => {
            eprintln!(
                "error: cannot listen on {}:{}: {e} (--port 0 picks any free port)",
                options.host, options.port
            );
            1
        }
        Err(studio::ServeError::Io(e)) => {
            eprintln!("error: the studio stopped: {e}");
            1
        }
    }
}

/// Open `url` in the user's browser; a machine without one gets a note, not an error.
fn open_browser(url: &str) {
    let tries: &[(&str, &[&str])] = if cfg!(target_os = "macos") {
        &[("open", &[])]
    } else if cfg!(windows) {
        &[("cmd", &["/C", "start", ""])]
    } else {
        &[("xdg-open", &[]), ("sensible-browser", &[])]
    };
    for (bin, pre) in tries {
        let started = std::process::Command::new(bin)
            .args(*pre)
            .arg(url)
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .spawn();
        if started.is_ok() {
            return;
        }
    }
    eprintln!("note: no browser could be started here; open {url} yourself");
}
