//! `fusemap`: multi-sensor occupancy-grid mapping.

mod commands;

use clap::{Parser, Subcommand};

/// Turns a robot's sensor observations into a probabilistic occupancy-grid map.
#[derive(Parser)]
#[command(name = "fusemap", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Insertion throughput on fixed synthetic workloads (a: corridor, b: corridor x500,
    /// c: 39 m box with 1,081-beam scans).
    Bench {
        /// Run one workload in this process (a, b or c); default: each in a child process.
        #[arg(long)]
        workload: Option<char>,
        /// One JSON object per line per workload instead of a table.
        #[arg(long)]
        json: bool,
    },
}

fn main() {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Bench { workload, json } => commands::bench::run(workload, json),
    };
    if let Err(e) = result {
        eprintln!("error: {}", format_chain(&e));
        std::process::exit(1);
    }
}

/// The error and its causes on one line.
fn format_chain(e: &anyhow::Error) -> String {
    let mut s = e.to_string();
    for cause in e.chain().skip(1) {
        let c = cause.to_string();
        if !s.contains(&c) {
            s.push_str(": ");
            s.push_str(&c);
        }
    }
    s.replace('\n', " ")
}
