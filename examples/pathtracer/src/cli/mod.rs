//! The command line: `optimize`, `render`, `all`, `experiment` and the other subcommands.
//!
//! One file per subcommand, each with its options (a `clap::Args` struct) and a `run` that
//! does the work; this file holds the parser, the dispatch and what several commands share.

mod all;
mod experiment;
mod export;
mod landscape;
mod optimize;
mod point;
mod render;
mod seeds;
mod stopping;
mod summarize;
mod timings;
mod values;

use std::time::Instant;

use clap::parser::ValueSource;
use clap::{ArgMatches, CommandFactory, FromArgMatches, Parser, Subcommand};

use crate::report::Result;
use crate::run::interrupt::{self, Interrupted};
use crate::tasks::{self, Task, View};

#[derive(Parser)]
#[command(
    version,
    about = "Plateau-free differentiable path tracing: the paper's tasks on a CPU path tracer"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render the reference, optimise from the start, write images, plot, CSV and summary.
    Optimize(optimize::Args),
    /// Render one image at the target (default), the start or given parameters, and print
    /// `render_seconds: X` (the render alone, scene set-up excluded), `render_cpu_seconds: C`,
    /// `paths: N`, `rays: M`.
    Render(render::Args),
    /// Write the task's scene at the target (default), the start or given parameters as
    /// `scene.json` (with its mesh and texture files) for another renderer to read.
    Export(export::Args),
    /// Every task with the plateau-free gradient and the finite-difference baseline, then
    /// results.md: our numbers beside the paper's.
    All(all::Args),
    /// Rewrites `results.md` in a directory of runs (as `all` leaves it) from their
    /// `summary.json` files.
    Summarize(summarize::Args),
    /// Several seeds studies (directories of runs of `all --seeds K`) side by side: each
    /// seed's parameter MSE per method, how many reach the paper's, median, range, seconds.
    Seeds(seeds::Args),
    /// The stop rule (--stop-when-stalled) replayed on finished full-length runs without
    /// rendering: renders at the stop against the budget, parameter MSE at the stop against
    /// at the end.
    Stopping(stopping::Args),
    /// Median render time of every task at its defaults (target parameters, seed 0, scene
    /// set-up excluded), as a markdown table.
    Timings(timings::Args),
    /// The loss along one coordinate through the target (or the start): a CSV of theta_i,
    /// the image MSE against the reference, and the loss smoothed by Gaussians of the given
    /// spreads (a quadrature over the same grid), to see plateaus and what smoothing does.
    Landscape(landscape::Args),
    /// One of the supplemental's experiments or the speed/accuracy study: CSV, plots and a
    /// markdown page in the output directory.
    Experiment(experiment::Args),
}

/// How every render of a command is made: the options `optimize` and `render` share.
#[derive(clap::Args, Clone, Debug, Default)]
struct RenderOptions {
    /// Samples per pixel of every render [default: the task's, supplemental Table 1].
    #[arg(long, allow_negative_numbers = true, value_parser = values::at_least(1u32))]
    spp: Option<u32>,
    /// Seed of the renderer's noise (and of the estimator's draws, in `optimize`).
    #[arg(long, default_value_t = 0, allow_negative_numbers = true, value_parser = values::at_least(0u64))]
    seed: u64,
    /// Horizontal field of view in degrees, replacing the task's [default: the task's].
    #[arg(long, allow_hyphen_values = true, value_parser = values::fov)]
    fov: Option<f64>,
    /// Resolution multiplier: 0.5 renders a quarter of the pixels, at most 64 [default: 1].
    #[arg(long, allow_hyphen_values = true, value_parser = values::scale)]
    scale: Option<f64>,
    /// Worker threads for rendering [default: all cores].
    #[arg(long, allow_negative_numbers = true, value_parser = values::at_least(1usize))]
    threads: Option<usize>,
}

impl RenderOptions {
    /// The view overrides these options ask for.
    fn view(&self) -> View {
        View {
            fov_degrees: self.fov,
            scale: self.scale,
        }
    }
}

/// Parses the command line and runs it. A bad command line (a value out of range, an unknown
/// name, a missing argument) is refused before any work, on one line, with exit code 2; a
/// failure while working is printed on one line and exits 1.
pub fn main() {
    let parsed = Cli::command()
        .try_get_matches()
        .and_then(|matches| Ok((Cli::from_arg_matches(&matches)?, matches)));
    let (cli, matches) = match parsed {
        Ok(parsed) => parsed,
        // --help and --version.
        Err(e) if !e.use_stderr() => {
            let _ = e.print();
            std::process::exit(0);
        }
        Err(e) => {
            eprintln!("{}", one_line(&e));
            std::process::exit(2);
        }
    };
    if let Err(e) = run_cli(cli, &matches) {
        if let Some(stop) = e.downcast_ref::<Interrupted>() {
            let resume = if stop.resume.is_empty() {
                // `all` and the experiments: the same command keeps the finished runs and
                // continues the others.
                command_line(&[])
            } else {
                stop.resume.clone()
            };
            eprintln!("interrupted; to continue: {resume}");
            std::process::exit(interrupt::EXIT_CODE);
        }
        eprintln!("error: {e}");
        std::process::exit(if e.is::<Usage>() { 2 } else { 1 });
    }
}

/// This process's command line, without the options `drop` (and their values) and the
/// testing option `--stop-after`, quoted for a POSIX shell.
fn command_line(drop: &[&str]) -> String {
    let mut args: Vec<String> = Vec::new();
    let mut skip_value = false;
    for arg in std::env::args() {
        if skip_value {
            skip_value = false;
            continue;
        }
        let name = arg.split('=').next().unwrap_or("");
        if drop.contains(&name) || name == "--stop-after" {
            skip_value = !arg.contains('=');
            continue;
        }
        args.push(arg);
    }
    shell_line(&args)
}

/// `args` as one line for a POSIX shell, each quoted if it needs to be.
fn shell_line(args: &[String]) -> String {
    args.iter()
        .map(|a| {
            if !a.is_empty()
                && a.chars()
                    .all(|c| c.is_ascii_alphanumeric() || "-_./=,:+@".contains(c))
            {
                a.clone()
            } else {
                format!("'{}'", a.replace('\'', "'\\''"))
            }
        })
        .collect::<Vec<_>>()
        .join(" ")
}

/// clap's message as one line: the error, then its tips ("a similar argument exists: ...")
/// after semicolons; the blank lines, the usage and the pointer to `--help` left out.
fn one_line(e: &clap::Error) -> String {
    let text = e.to_string();
    let mut message: Vec<&str> = Vec::new();
    let mut tips: Vec<&str> = Vec::new();
    for line in text.lines().map(str::trim) {
        if line.starts_with("Usage:") || line.starts_with("For more information") {
            break;
        }
        if line.starts_with("tip:") {
            tips.push(line);
        } else if !line.is_empty() {
            message.push(line);
        }
    }
    let mut one = message.join(" ");
    for tip in tips {
        one.push_str("; ");
        one.push_str(tip);
    }
    one
}

/// A command line that parses but asks for something impossible (arguments that exclude each
/// other, a parameter count that does not fit the task): exit code 2, like a parse error.
#[derive(Debug)]
struct Usage(String);

impl std::fmt::Display for Usage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for Usage {}

/// Refuses `--polish` with a method other than polished (`optimize` and `all`), before any work.
fn check_polish(polish: Option<f64>, method: crate::run::Method) -> Result<()> {
    match polish {
        Some(share) if method != crate::run::Method::Polished => Err(usage(format!(
            "--polish {share}: it is the share of --method polished, not of --method {}; allowed: drop --polish, or --method polished",
            method.as_arg()
        ))),
        _ => Ok(()),
    }
}

/// A [`Usage`] error, boxed.
fn usage(message: String) -> Box<dyn std::error::Error + Send + Sync> {
    Box::new(Usage(message))
}

/// Whether the argument `id` (a field's name: `seed`, `no_anneal`) was written on the command
/// line, rather than left to its default (`id` must be one of the command's arguments).
fn given(matches: &ArgMatches, id: &str) -> bool {
    matches.value_source(id) == Some(ValueSource::CommandLine)
}

/// Runs one parsed command line (`matches`: what clap saw, to tell a value written from a
/// default).
fn run_cli(cli: Cli, matches: &ArgMatches) -> Result<()> {
    match cli.command {
        Command::Optimize(args) => {
            let m = matches.subcommand_matches("optimize");
            optimize::run(args, &|id| m.is_some_and(|m| given(m, id)))
        }
        Command::Render(args) => render::run(args),
        Command::Export(args) => export::run(args),
        Command::All(args) => all::run(args),
        Command::Summarize(args) => summarize::run(args),
        Command::Seeds(args) => seeds::run(args),
        Command::Stopping(args) => stopping::run(args),
        Command::Timings(args) => timings::run(args),
        Command::Landscape(args) => landscape::run(args),
        Command::Experiment(args) => experiment::run(args),
    }
}

/// The task called `name`, or an error listing the tasks.
fn find_task(name: &str) -> Result<Task> {
    tasks::by_name(name).ok_or_else(|| {
        let names: Vec<_> = tasks::names().collect();
        format!("unknown task {name:?}; the tasks are {}", names.join(", ")).into()
    })
}

/// Runs `f` on a rayon pool of `threads` workers (the global pool if `None`).
fn with_threads<T>(threads: Option<usize>, f: impl FnOnce() -> Result<T> + Send) -> Result<T>
where
    T: Send,
{
    match threads {
        None => f(),
        Some(0) => Err("--threads must be at least 1".into()),
        Some(n) => rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()?
            .install(f),
    }
}

/// Calls `f` `repeat` times (at least once) and returns the median of its wall times.
fn median_seconds(repeat: usize, mut f: impl FnMut()) -> f64 {
    let mut times: Vec<f64> = (0..repeat.max(1))
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed().as_secs_f64()
        })
        .collect();
    times.sort_by(f64::total_cmp);
    times[times.len() / 2]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// clap's own consistency checks of every subcommand (names, conflicts, defaults): in a
    /// release build they run only here.
    #[test]
    fn the_command_line_is_consistent() {
        Cli::command().debug_assert();
    }

    /// The one-line message of a refused command line (panics if it parses).
    fn refused(line: &str) -> String {
        match Cli::try_parse_from(line.split_whitespace()) {
            Ok(_) => panic!("accepted: {line}"),
            Err(e) => {
                assert_eq!(e.exit_code(), 2, "{line}");
                one_line(&e)
            }
        }
    }

    /// Asserts that `line` is refused on one line naming `argument`, `value` and `allowed`.
    fn refused_naming(line: &str, argument: &str, value: &str, allowed: &str) {
        let message = refused(&format!("pathtracer {line}"));
        assert!(!message.contains('\n'), "{line}: {message}");
        for part in [argument, &format!("'{value}'"), allowed] {
            assert!(
                message.contains(part),
                "{line}: {part:?} not in {message:?}"
            );
        }
    }

    /// As [`refused_naming`], the argument and the value being the line's last two words.
    fn refused_last(line: &str, allowed: &str) {
        let words: Vec<&str> = line.split_whitespace().collect();
        let [.., argument, value] = words[..] else {
            panic!("{line}: too short")
        };
        refused_naming(line, argument, value, allowed);
    }

    /// Every bad value is refused while parsing, on one line naming the argument, the value
    /// and what is allowed: negative numbers are read as values, then refused.
    #[test]
    fn bad_values_are_refused_with_the_argument_the_value_and_what_is_allowed() {
        for option in [
            "--iterations",
            "--samples",
            "--spp",
            "--threads",
            "--eval-every",
        ] {
            for value in ["0", "-5", "x"] {
                refused_last(&format!("optimize shadow {option} {value}"), ">= 1");
            }
        }
        for option in ["--sigma0", "--lr", "--scale", "--budget", "--fd-step"] {
            for value in ["0", "-1", "NaN", "inf", "-inf"] {
                refused_last(
                    &format!("optimize shadow {option} {value}"),
                    "finite number > 0",
                );
            }
        }
        // A scale or an N whose buffers could not be allocated is refused while parsing (the
        // allocation would overflow).
        for value in ["65", "1e300"] {
            refused_last(&format!("optimize shadow --scale {value}"), "<= 64");
        }
        for value in ["65537", "18446744073709551614"] {
            refused_last(&format!("optimize shadow --samples {value}"), "<= 65536");
        }
        for value in ["0", "180", "-10", "nan"] {
            refused_last(&format!("render cup --out a.png --fov {value}"), "< 180");
        }
        for line in [
            "render cup --out a.png --repeat 0",
            "all --seeds 0",
            "experiment fig1 --seeds -2",
            "timings --repeat 0",
        ] {
            refused_last(line, ">= 1");
        }
        for (line, allowed) in [
            ("landscape cup --from 0 --to 1 --steps 1", ">= 2"),
            ("landscape cup --to 1 --from -inf", "finite"),
            ("render cup --out cup.jpg", ".png or .exr"),
            ("optimize shadow --sampling best", "radial"),
            ("optimize shadow --method magic", "plateau"),
        ] {
            refused_last(line, allowed);
        }
        for (line, argument, value, allowed) in [
            ("optimize nope", "[TASK]", "nope", "cup, shadow"),
            ("experiment fig9", "<NAME>", "fig9", "fig1"),
            ("all --tasks cup,nope", "--tasks", "nope", "cup, shadow"),
            (
                "render cup --params 0.1,nan --out a.png",
                "--params",
                "nan",
                "finite",
            ),
            (
                "landscape cup --from 0 --to 1 --sigmas 0.1,-1",
                "--sigmas",
                "-1",
                "> 0",
            ),
        ] {
            refused_naming(line, argument, value, allowed);
        }
    }

    /// An existing file is no output directory.
    #[test]
    fn an_existing_file_is_refused_as_an_output_directory() {
        let file = std::env::temp_dir().join(format!("plateau-cli-{}", std::process::id()));
        std::fs::write(&file, b"x").unwrap();
        for command in [
            "optimize shadow --out",
            "all --out",
            "experiment fig1 --out",
        ] {
            let message = refused(&format!("pathtracer {command} {}", file.display()));
            assert!(
                message.contains("--out") && message.contains("not a file"),
                "{message}"
            );
        }
        std::fs::remove_file(&file).unwrap();
    }

    /// Good values, negative ones where they are allowed included, parse.
    #[test]
    fn good_values_parse() {
        for line in [
            "optimize shadow --iterations 3 --sigma0 0.5 --lr 0.01 --fov 60 --scale 0.5 --eval-every 1",
            "render shadow --params -1.5,1.0 --out a.exr",
            "landscape shadow --coordinate 1 --from -3 --to -1",
            "experiment gradient-quality --quick --seeds 2",
        ] {
            let args = format!("pathtracer {line}");
            assert!(Cli::try_parse_from(args.split_whitespace()).is_ok(), "{line}");
        }
    }

    /// Every option of every command says what it does, and, where it takes a value and is
    /// not required, its default.
    #[test]
    fn every_option_documents_itself_and_its_default() {
        let cli = Cli::command();
        for command in cli.get_subcommands() {
            for arg in command.get_arguments() {
                let id = arg.get_id().as_str();
                if id == "help" {
                    continue;
                }
                let help = arg.get_help().map(|h| h.to_string()).unwrap_or_default();
                assert!(!help.is_empty(), "{} --{id}: no help", command.get_name());
                let takes_value = arg.get_num_args().is_some_and(|n| n.takes_values());
                if takes_value && !arg.is_required_set() && arg.get_default_values().is_empty() {
                    assert!(
                        help.contains("[default:"),
                        "{} --{id}: no default in {help:?}",
                        command.get_name()
                    );
                }
            }
        }
    }
}
