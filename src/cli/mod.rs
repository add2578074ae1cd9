//! Command-line flags (clap derive). Flags stop here: each command gets a validated config struct.

mod bench;
mod eval;
mod resolve;
mod trials;
mod values;

pub(crate) use bench::BenchCommand;
use bench::BenchTrainArgs;
pub(crate) use eval::{EvalArgs, PredictArgs};
use trials::parse_crop;
pub(crate) use trials::{CollectArgs, ImproveArgs, MergeArgs, TrialArgs};
pub(crate) use values::PrecisionChoice;

mod given;
mod outputs;
mod scoped;
use given::Given;
use scoped::{ObjectsAndSplit, ObjectsArg, Scoped};

use std::path::PathBuf;

use anyhow::{bail, Context as _};
use clap::{Args, Parser, Subcommand};

use crate::commands;
use crate::commands::bench::{BenchConfig, PeerPython};
use crate::commands::scene::{SceneConfig, SceneSource};
use crate::commands::Context;
use crate::data::input::InputKind;
use crate::model::autotune::Workload;
use crate::model::config::TrainConfig;
use crate::sim::WorkcellConfig;
use values::{named, non_negative_up_to, parse_label_address, parse_pixel, positive_up_to};

/// Teach a simulated UR5 to pick up objects it has never seen, from a few dozen labelled grasps.
#[derive(Debug, Parser)]
#[command(name = "graspmap", version, about, allow_negative_numbers = true)]
pub(crate) struct Cli {
    #[command(flatten)]
    pub(crate) global: GlobalArgs,
    #[command(subcommand)]
    pub(crate) command: Command,
}

/// Flags every command takes, and (before the command's name) the scoped flags of
/// [`scoped`], for the commands that take them.
#[derive(Debug, Args, Clone)]
pub(crate) struct GlobalArgs {
    /// Data directory: labels in DIR/labels, model and evaluations in DIR/affordance.
    #[arg(long, global = true, default_value = "data", value_name = "DIR")]
    pub(crate) data: PathBuf,
    /// Directory of object models (scene, grasp, label, eval, collect, improve) [default: the 15
    /// bundled models].
    #[arg(long = "objects-dir", value_name = "DIR")]
    pub(crate) objects_dir: Option<PathBuf>,
    /// Train/test split JSON (label, eval, collect, improve) [default: <objects-dir>/split.json].
    #[arg(long, value_name = "FILE")]
    pub(crate) split: Option<PathBuf>,
    /// Worker threads for CPU-heavy work [default: all cores].
    #[arg(long, global = true, value_name = "N", value_parser = clap::value_parser!(u16).range(1..))]
    pub(crate) threads: Option<u16>,
    /// Also write the results as JSON to PATH ('-' = stdout); an existing file is replaced only
    /// when it is an earlier graspmap report.
    #[arg(long, global = true, value_name = "PATH")]
    pub(crate) json: Option<PathBuf>,
    /// Print only results and errors, no progress.
    #[arg(long, short, global = true)]
    pub(crate) quiet: bool,
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub(crate) enum Command {
    /// Drop objects into bin 1 and save the top-down camera image.
    #[command(allow_negative_numbers = true)]
    Scene(SceneArgs),
    /// Drop one object and run one simulated pick attempt.
    #[command(allow_negative_numbers = true)]
    Grasp(GraspArgs),
    /// Collect verified grasp labels for the training objects.
    #[command(allow_negative_numbers = true)]
    Label(LabelArgs),
    /// Train the affordance model on the labels.
    #[command(allow_negative_numbers = true)]
    Train(TrainArgs),
    /// Let a policy pick objects in simulation and report how it did.
    #[command(allow_negative_numbers = true)]
    Eval(EvalArgs),
    /// Try grasps in clutter on the training objects and store every attempt (trials).
    #[command(allow_negative_numbers = true)]
    Collect(CollectArgs),
    /// Combine the shard stores of one `collect --shard I/N` run into one trial store.
    Merge(MergeArgs),
    /// The self-supervised loop: collect trials with the current model, retrain, repeat.
    #[command(allow_negative_numbers = true)]
    Improve(ImproveArgs),
    /// Run the trained model on a 128 × 128 RGB image and print its best grasp.
    #[command(allow_negative_numbers = true)]
    Predict(PredictArgs),
    /// Write one self-contained HTML page of the whole run (labels, training, evaluations).
    #[command(allow_negative_numbers = true)]
    Report(ReportArgs),
    /// Measure speed against the Python PyTorch peer.
    #[command(subcommand, allow_negative_numbers = true)]
    Bench(BenchCommand),
}

/// `graspmap train`.
#[derive(Debug, Args)]
pub(crate) struct TrainArgs {
    /// Epochs to train.
    #[arg(long, default_value_t = TrainConfig::default().epochs, value_parser = clap::value_parser!(u32).range(1..))]
    pub(crate) epochs: u32,
    /// Images per optimiser step.
    #[arg(long, default_value_t = TrainConfig::default().batch_size as u32, value_parser = clap::value_parser!(u32).range(1..))]
    pub(crate) batch_size: u32,
    /// Initial Adam learning rate (above 0, at most 1).
    #[arg(long, default_value_t = TrainConfig::default().lr, value_parser = positive_up_to::<f64>(1.0))]
    pub(crate) lr: f64,
    /// Seed of the 90/10 split, initial weights, data order and augmentation.
    #[arg(long, default_value_t = 0)]
    pub(crate) seed: u64,
    /// Continue from DATA/affordance/last.* exactly where it stopped. Without it, a data dir
    /// that already holds a model is resumed only when its settings and labels match, and
    /// refused otherwise.
    #[arg(long)]
    pub(crate) resume: bool,
    /// Train anew over an existing model; the old best.safetensors (and best.json) are kept as
    /// best.prev.safetensors (and best.prev.json).
    #[arg(long, conflicts_with = "resume")]
    pub(crate) force: bool,
    /// Arithmetic of training.
    #[arg(long, value_enum, default_value_t = PrecisionChoice::Auto)]
    pub(crate) precision: PrecisionChoice,
    /// What the network sees; rgbd needs DATA/labels/<Object>_<k>_depth.png beside every label.
    #[arg(long, value_parser = named::<InputKind>(), default_value = "rgb")]
    pub(crate) input: InputKind,
    /// Train on PX × PX crops around each supervised pixel (a multiple of 4, at least 32; 0 =
    /// whole images). Inference and validation always see whole images.
    #[arg(long, value_name = "PX", default_value_t = TrainConfig::default().crop, value_parser = parse_crop)]
    pub(crate) crop: u32,
    /// Also train on the trials of this store (as `graspmap collect` writes it); repeat for
    /// several (each store once). Each trial supervises only its executed pixel and rotation.
    #[arg(long, value_name = "DIR")]
    pub(crate) trials: Vec<PathBuf>,
    /// Leave the labels out: train on --trials alone.
    #[arg(long, requires = "trials")]
    pub(crate) no_labels: bool,
    /// A trial's total loss weight, against a label's 1 spread over its pixels (above 0, at
    /// most 1).
    #[arg(long, value_name = "W", default_value_t = TrainConfig::default().trial_weight, value_parser = positive_up_to::<f32>(1.0))]
    pub(crate) trial_weight: f32,
    /// σ in pixels of the Gaussian window a trial weights around its pixel (0 = the pixel
    /// alone; at most 8).
    #[arg(long, value_name = "PX", default_value_t = 0.0, value_parser = non_negative_up_to(8.0))]
    pub(crate) trial_sigma: f32,
    /// Start from this checkpoint's weights instead of fresh ones (fine-tuning).
    #[arg(long, value_name = "PATH", conflicts_with = "resume")]
    pub(crate) start_from: Option<PathBuf>,
    /// Where the model goes [default: DATA/affordance].
    #[arg(long, value_name = "DIR")]
    pub(crate) out_dir: Option<PathBuf>,
}

/// `graspmap report`.
#[derive(Debug, Args)]
pub(crate) struct ReportArgs {
    /// The page; the files it shows go to <stem>_files/ beside it [default: DATA/report.html].
    #[arg(long, value_name = "HTML")]
    pub(crate) out: Option<PathBuf>,
    /// Then serve the report at /report and the labels page at /labels (deletes included)
    /// until Ctrl-C, without labelling.
    #[arg(long)]
    pub(crate) serve: bool,
    /// --serve: the port (0 picks a free one and prints it).
    #[arg(long, default_value_t = 8000, requires = "serve")]
    pub(crate) port: u16,
    /// --serve: the address to bind; anything but loopback prints a warning.
    #[arg(long, default_value = "127.0.0.1", requires = "serve")]
    pub(crate) host: std::net::IpAddr,
    /// Replace an existing --out page that graspmap did not write.
    #[arg(long)]
    pub(crate) force: bool,
}

/// The label flags that only the scripted clicker reads.
const SCRIPTED_ONLY: [&str; 6] = [
    "clicks",
    "interactive",
    "web",
    "check",
    "delete",
    "backfill_depth",
];

/// `graspmap label`.
#[derive(Debug, Args)]
#[command(group = clap::ArgGroup::new("clicker").args(["clicks", "interactive", "web"]))]
pub(crate) struct LabelArgs {
    /// Successful labels wanted per training object.
    #[arg(long, default_value_t = 12, value_parser = clap::value_parser!(u32).range(1..))]
    pub(crate) per_object: u32,
    /// Rounds allowed per object before giving up on it (an error naming the object).
    #[arg(long, default_value_t = 40, value_parser = clap::value_parser!(u32).range(1..))]
    pub(crate) max_rounds: u32,
    /// Base seed: round r of training object j drops with seed + 100·j + r.
    #[arg(long, default_value_t = 0)]
    pub(crate) seed: u64,
    /// Take clicks from a JSON list of {"object", "x", "y", "angle"}, in order, one per round.
    #[arg(long, value_name = "FILE")]
    pub(crate) clicks: Option<PathBuf>,
    /// Click by hand: the image goes to --preview, commands come from stdin.
    #[arg(long)]
    pub(crate) interactive: bool,
    /// Click by hand in the browser: serves the labelling page (and the labels page at /labels)
    /// and prints its address; Ctrl-C stops it.
    #[arg(long)]
    pub(crate) web: bool,
    /// --web: the port to serve on (0 picks a free one and prints it).
    #[arg(long, default_value_t = 8000, requires = "web")]
    pub(crate) port: u16,
    /// --web: the address to bind. Anything but loopback lets other machines run the robot,
    /// and prints a warning.
    #[arg(long, default_value = "127.0.0.1", requires = "web")]
    pub(crate) host: std::net::IpAddr,
    /// Where --interactive writes the image with the cursor's grasp [default: DATA/labels/preview.png].
    #[arg(long, value_name = "PNG", requires = "interactive")]
    pub(crate) preview: Option<PathBuf>,
    /// Scripted clicks: standard deviation of the click position noise in pixels (0 to 64).
    #[arg(long, default_value_t = 0.0, value_parser = non_negative_up_to(64.0),
          conflicts_with_all = SCRIPTED_ONLY)]
    pub(crate) click_noise_px: f32,
    /// Scripted clicks: standard deviation of the angle noise in degrees, before snapping to
    /// 22.5° (0 to 180).
    #[arg(long, default_value_t = 0.0, value_parser = non_negative_up_to(180.0),
          conflicts_with_all = SCRIPTED_ONLY)]
    pub(crate) angle_noise_deg: f32,
    /// Delete existing labels and start over.
    #[arg(long, conflicts_with = "check")]
    pub(crate) force: bool,
    /// Delete one label, e.g. YcbHammer:3: that object's later labels (and their sidecar files)
    /// move down one number in one crash-safe step; the next labelling run refills it.
    #[arg(long, value_name = "OBJECT:K", value_parser = parse_label_address,
          conflicts_with_all = ["clicks", "interactive", "web", "check", "force", "per_object", "max_rounds", "seed", "clutter"])]
    pub(crate) delete: Option<(String, usize)>,
    /// Only validate the existing dataset; exit 2 if anything is wrong.
    #[arg(long, conflicts_with_all = ["clicks", "interactive", "web", "per_object", "max_rounds", "seed", "clutter"])]
    pub(crate) check: bool,
    /// Objects dropped per round: the round's object and K − 1 other training objects.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..))]
    pub(crate) clutter: u32,
    /// Write the missing <Object>_<k>_depth.png of a dataset graspmap labelled before depth
    /// files existed, by replaying its rounds' drops.
    #[arg(long, conflicts_with_all = ["check", "force", "clicks", "interactive", "web", "delete", "per_object", "max_rounds", "seed", "clutter"])]
    pub(crate) backfill_depth: bool,
    #[command(flatten)]
    pub(crate) scope: ObjectsAndSplit,
}

/// `graspmap scene`.
#[derive(Debug, Args)]
pub(crate) struct SceneArgs {
    /// Comma-separated object names, dropped in this order.
    #[arg(long, value_delimiter = ',', required_unless_present = "load", num_args = 1..)]
    pub(crate) objects: Vec<String>,
    /// Seed of the drop poses.
    #[arg(long, default_value_t = 0, conflicts_with = "load")]
    pub(crate) seed: u64,
    /// Place the objects as this scene file lists them instead of dropping them: graspmap's
    /// JSON (as --save writes it) or one of VPG's test cases (docs/scenes.md).
    #[arg(long, value_name = "FILE", conflicts_with = "objects")]
    pub(crate) load: Option<PathBuf>,
    /// Also write the settled scene as a scene file (graspmap's JSON), which --load and
    /// `eval --task scenes --scenes FILE` replay; --out then shows the scene as replayed.
    #[arg(long, value_name = "FILE")]
    pub(crate) save: Option<PathBuf>,
    /// Output RGB image (.png).
    #[arg(long, value_name = "PNG")]
    pub(crate) out: PathBuf,
    /// Also write the depth image as 16-bit PNG in millimetres.
    #[arg(long, value_name = "PNG")]
    pub(crate) depth: Option<PathBuf>,
    /// Replace --out and --depth when they exist.
    #[arg(long)]
    pub(crate) force: bool,
    #[command(flatten)]
    pub(crate) objects_dir: ObjectsArg,
}

/// `graspmap grasp`.
#[derive(Debug, Args)]
#[command(group = clap::ArgGroup::new("policy").required(true).args(["pixel", "oracle", "random"]))]
pub(crate) struct GraspArgs {
    /// Object to drop into bin 1.
    #[arg(long)]
    pub(crate) object: String,
    /// Seed of the drop pose (and of --random's choice).
    #[arg(long, default_value_t = 0)]
    pub(crate) seed: u64,
    /// Grasp centre as column,row in the 128 × 128 image (needs --angle).
    #[arg(long, value_name = "U,V", requires = "angle")]
    pub(crate) pixel: Option<String>,
    /// Grasp angle in degrees from -360 to 360, clockwise in the image; normalised mod 180.
    #[arg(
        long,
        value_name = "DEG",
        allow_negative_numbers = true,
        requires = "pixel",
        conflicts_with_all = ["oracle", "random"]
    )]
    pub(crate) angle: Option<f64>,
    /// Let the oracle planner choose the grasp from ground-truth mask and depth.
    #[arg(long)]
    pub(crate) oracle: bool,
    /// A uniformly random pixel on bin 1's floor area and a random angle.
    #[arg(long)]
    pub(crate) random: bool,
    /// Write a video of the attempt from an oblique view: .mp4 (H.264) or .gif.
    #[arg(long, value_name = "VIDEO")]
    pub(crate) record: Option<PathBuf>,
    /// Grip force per finger in newtons (above 0, at most 200).
    #[arg(long, default_value_t = WorkcellConfig::default().grip_force, value_parser = positive_up_to::<f32>(200.0))]
    pub(crate) grip_force: f32,
    /// Also save the camera image with the grasp drawn (.png).
    #[arg(long, value_name = "PNG")]
    pub(crate) image: Option<PathBuf>,
    /// Replace --image when it exists (--record replaces an earlier video without it).
    #[arg(long)]
    pub(crate) force: bool,
    #[command(flatten)]
    pub(crate) objects_dir: ObjectsArg,
}

/// Parses flags and runs the chosen command.
pub fn run() -> anyhow::Result<()> {
    use clap::{CommandFactory as _, FromArgMatches as _};
    let parsed = Cli::command()
        .try_get_matches()
        .and_then(|matches| Cli::from_arg_matches(&matches).map(|cli| (cli, matches)));
    let (cli, matches) = match parsed {
        Ok(parsed) => parsed,
        Err(e) => return parse_failure(e),
    };
    init_logging(cli.global.quiet);
    // The long writers stop at a safe point on the first Ctrl-C; the other commands keep the
    // default, which ends them at once.
    let serves_report = matches!(&cli.command, Command::Report(report) if report.serve);
    if serves_report
        || matches!(
            cli.command,
            Command::Label(_)
                | Command::Train(_)
                | Command::Eval(_)
                | Command::Collect(_)
                | Command::Improve(_)
        )
    {
        crate::interrupt::install().context("installing the Ctrl-C handler")?;
    }
    let before = scoped::Resolved {
        objects_dir: cli.global.objects_dir.clone(),
        split: cli.global.split.clone(),
    };
    let scoped = cli.command.scoped().resolve(cli.command.name(), before)?;
    let given = Given::of(&matches);
    given::refuse_unread(&given, cli.command.name(), cli.command.unread_globals())?;
    let context = cli.global.context(cli.command.name(), scoped)?;
    crate::model::autotune::set_quiet(context.quiet);
    dispatch(&context, cli.command, &given)
}

/// A command line clap refused (or `--help`, `--version`): one line on stderr, exit status 2.
fn parse_failure(e: clap::Error) -> anyhow::Result<()> {
    use clap::error::ErrorKind;
    if matches!(e.kind(), ErrorKind::DisplayHelp | ErrorKind::DisplayVersion) {
        // `graspmap --help | head -1` closes the pipe early: the reader has what it
        // wanted, which is no error.
        return match e.print() {
            Err(io) if io.kind() != std::io::ErrorKind::BrokenPipe => Err(io.into()),
            _ => Ok(()),
        };
    }
    if matches!(
        e.kind(),
        ErrorKind::MissingSubcommand | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand
    ) {
        let names: Vec<String> = <Cli as clap::CommandFactory>::command()
            .get_subcommands()
            .map(|c| c.get_name().to_owned())
            .collect();
        bail!(
            "no command given: choose one of {} (see graspmap --help)",
            names.join(", ")
        );
    }
    // clap's message names the flag and the fix over a few lines; fold it into one.
    let text = e.to_string();
    let message = text
        .lines()
        .take_while(|l| !l.trim().is_empty())
        .map(str::trim)
        .collect::<Vec<_>>()
        .join(" ");
    bail!(
        "{} (see graspmap --help)",
        message.trim_start_matches("error: ")
    );
}

/// Resolves the command's flags into its config, checks every file it will read and write
/// (outputs::check), and runs it.
fn dispatch(context: &Context, command: Command, given: &Given) -> anyhow::Result<()> {
    let data = context.data.clone();
    match command {
        Command::Scene(args) => scene(context, args),
        Command::Grasp(args) => {
            let force = args.force;
            let config = args.config()?;
            outputs::grasp(context, &config, force).check()?;
            commands::grasp::run(context, config)
        }
        Command::Label(args) => {
            let config = args.config(&data);
            outputs::label(context, &config).check()?;
            commands::label::run(context, config)
        }
        Command::Train(args) => {
            let options = args.options(&data, given)?;
            outputs::train(context, &options).check()?;
            commands::train::run(context, options)
        }
        Command::Eval(args) => {
            let config = args.config(&data, given)?;
            outputs::eval(context, &config).check()?;
            commands::eval::run(context, config)
        }
        Command::Collect(args) => match args.check {
            true => {
                outputs::base(context, None).check()?;
                commands::collect::check(context, &args.out.unwrap_or_else(|| data.join("trials")))
            }
            false => {
                let config = args.config(&data, given)?;
                outputs::collect(context, &config).check()?;
                commands::collect::run(context, config)
            }
        },
        Command::Merge(args) => {
            let config = commands::merge::MergeConfig {
                inputs: args.inputs,
                out: args.out,
                allow_partial: args.allow_partial,
            };
            outputs::merge(context, &config, args.force)?.check()?;
            commands::merge::run(context, config)
        }
        Command::Improve(args) => {
            let config = args.config(&data, given)?;
            outputs::improve(context, &config).check()?;
            commands::improve::run(context, config)
        }
        Command::Predict(args) => {
            let (force, named) = (args.force, args.out.is_some());
            let config = args.config(&data);
            outputs::predict(context, &config, force, named).check()?;
            commands::predict::run(context, config)
        }
        Command::Report(args) => {
            let (force, named) = (args.force, args.out.is_some());
            let config = args.config(&data)?;
            outputs::report(context, &config, force, named)?.check()?;
            commands::report::run(context, config)
        }
        Command::Bench(BenchCommand::Train(args)) => bench_train(context, args),
        Command::Bench(BenchCommand::Precision) => {
            outputs::base(context, None).check()?;
            commands::bench::precision(context)
        }
    }
}

/// `graspmap scene`.
fn scene(context: &Context, args: SceneArgs) -> anyhow::Result<()> {
    let config = SceneConfig {
        source: match args.load {
            Some(file) => SceneSource::Load(file),
            None => SceneSource::Drop {
                objects: args.objects,
                seed: args.seed,
            },
        },
        out: args.out,
        depth: args.depth,
        save: args.save,
    };
    outputs::scene(context, &config, args.force).check()?;
    commands::scene::run(context, config)
}

/// `graspmap bench train`.
fn bench_train(context: &Context, args: BenchTrainArgs) -> anyhow::Result<()> {
    let mut files = outputs::base(context, None);
    files.input("the --python this command runs", args.python.as_deref());
    files.check()?;
    commands::bench::run(
        context,
        BenchConfig {
            steps: args.steps,
            rounds: args.rounds,
            precision: args.precision.resolve(Workload::Train),
            peer: match (args.no_peer, args.python) {
                (true, _) => None,
                (false, Some(path)) => Some(PeerPython::Given(path)),
                (false, None) => Some(PeerPython::Checkout),
            },
        },
    )
}

impl Command {
    /// The subcommand as typed.
    fn name(&self) -> &'static str {
        match self {
            Command::Scene(_) => "scene",
            Command::Grasp(_) => "grasp",
            Command::Label(_) => "label",
            Command::Train(_) => "train",
            Command::Eval(_) => "eval",
            Command::Collect(_) => "collect",
            Command::Merge(_) => "merge",
            Command::Improve(_) => "improve",
            Command::Predict(_) => "predict",
            Command::Report(_) => "report",
            Command::Bench(_) => "bench",
        }
    }

    /// The global flags the command never reads: refused when typed, so that none does nothing.
    fn unread_globals(&self) -> &'static [&'static str] {
        match self {
            // One simulation on one thread, and nothing read from or written to the data dir.
            Command::Scene(_) | Command::Grasp(_) => &["data", "threads"],
            _ => &[],
        }
    }

    /// The scoped flags the command takes, as given after its name.
    fn scoped(&self) -> Scoped<'_> {
        match self {
            Command::Scene(a) => Scoped {
                objects: Some(&a.objects_dir),
                split: None,
            },
            Command::Grasp(a) => Scoped {
                objects: Some(&a.objects_dir),
                split: None,
            },
            Command::Label(a) => a.scope.scoped(),
            Command::Eval(a) => a.scope.scoped(),
            Command::Collect(a) => a.scope.scoped(),
            Command::Improve(a) => a.scope.scoped(),
            Command::Train(_)
            | Command::Predict(_)
            | Command::Report(_)
            | Command::Bench(_)
            | Command::Merge(_) => Scoped::default(),
        }
    }
}

fn init_logging(quiet: bool) {
    let default = if quiet { "warn" } else { "info" };
    let filter = tracing_subscriber::EnvFilter::try_from_env("GRASPMAP_LOG")
        .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new(default));
    use std::io::IsTerminal as _;
    let _ = tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        .with_ansi(std::io::stderr().is_terminal())
        .without_time()
        .with_target(false)
        .try_init();
}

#[cfg(test)]
mod tests {
    use super::values::parse_seed_list;
    use super::*;
    use crate::named::Named;
    use crate::present::eval_report::Task;

    #[test]
    fn pixel_parsing_rejects_out_of_image_and_garbage() {
        assert_eq!(parse_pixel("64,70").unwrap(), (64, 70));
        assert_eq!(parse_pixel(" 0 , 127 ").unwrap(), (0, 127));
        assert!(parse_pixel("128,3")
            .unwrap_err()
            .to_string()
            .contains("outside"));
        assert!(parse_pixel("-1,3")
            .unwrap_err()
            .to_string()
            .contains("'-1'"));
        assert!(parse_pixel("12")
            .unwrap_err()
            .to_string()
            .contains("two integers"));
    }

    #[test]
    fn seed_lists_take_ranges_and_lists_and_reject_nonsense() {
        assert_eq!(parse_seed_list("1-4").unwrap().0, [1, 2, 3, 4]);
        assert_eq!(parse_seed_list("0,1000,2000").unwrap().0, [0, 1000, 2000]);
        assert_eq!(parse_seed_list("1-3, 7").unwrap().0, [1, 2, 3, 7]);
        assert!(parse_seed_list("5-2").unwrap_err().contains("empty range"));
        assert!(parse_seed_list("1,x").unwrap_err().contains("'x'"));
        assert!(parse_seed_list("1,2,1")
            .unwrap_err()
            .contains("repeats seed 1"));
        assert!(parse_seed_list("").is_err());
    }

    #[test]
    fn n_past_action_takes_both_spellings() {
        for flag in ["--n_past_action", "--n-past-action"] {
            let cli = Cli::try_parse_from(["graspmap", "eval", "--task", "empty_bin", flag, "8"])
                .unwrap();
            let Command::Eval(args) = cli.command else {
                panic!("parsed as another command")
            };
            assert_eq!(args.n_past_action, 8);
            assert_eq!(args.task, Task::EmptyBin);
        }
    }

    #[test]
    fn task_names_are_spelled_as_the_reference_spells_them() {
        let names: Vec<&str> = Task::ALL.iter().map(|t| t.name()).collect();
        assert_eq!(names, ["train", "test", "empty_bin", "scenes"]);
        let cli = Cli::try_parse_from(["graspmap", "eval", "--task", "empty_bin"]).unwrap();
        let Command::Eval(args) = cli.command else {
            panic!("parsed as another command")
        };
        assert_eq!(args.task, Task::EmptyBin);
        assert!(Cli::try_parse_from(["graspmap", "eval", "--task", "emptybin"]).is_err());
    }

    #[test]
    fn cli_definition_is_consistent() {
        use clap::CommandFactory;
        Cli::command().debug_assert();
    }
}
