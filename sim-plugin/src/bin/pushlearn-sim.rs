//! `pushlearn-sim`: the thesis world on ODE, as a daemon (`serve`, also what
//! a bare `pushlearn-sim` does) or for the calibration sweep.
//!
//! Each subcommand lives in its own function; the daemon itself is
//! [`sim_plugin::server`].

use std::io::Write;
use std::net::{IpAddr, SocketAddr};
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Arc;
use std::time::Duration;

use anyhow::{bail, Context};
use clap::builder::TypedValueParser as _;
use clap::{Args, Parser, Subcommand, ValueEnum};
use sim_plugin::replay::Replay;
use sim_plugin::scene::DEFAULT_SCENE;
use sim_plugin::server::{
    Config, Latency, Server, Timing, DEFAULT_CLIENT_QUEUE, DEFAULT_MAX_CLIENTS, DEFAULT_PORT,
    DEFAULT_REAL_TIME_RATE,
};
use sim_plugin::world::Engine;
use sim_plugin::{Scene, SweepOptions, SweepRow};

#[derive(Debug, Parser)]
#[command(
    name = "pushlearn-sim",
    version,
    about = "The thesis's table-top pushing world on ODE",
    long_about = "The thesis's table-top pushing world on ODE (Debian's libode, double precision): \
                  an actuator sphere driven by velocity commands pushes blocks on a plane in 1 ms steps.\n\n\
                  Scenes are TOML files or the embedded `one_block` (default), `two_blocks` and `objects`; \
                  see docs/world.md for the format.\n\n\
                  Without a subcommand, `pushlearn-sim [OPTIONS]` is `pushlearn-sim serve [OPTIONS]`.",
    args_conflicts_with_subcommands = true
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Cmd>,
    #[command(flatten)]
    serve: ServeArgs,
}

#[derive(Debug, Subcommand)]
enum Cmd {
    /// Serve the world to TCP clients (the default): publish world states, accept commands.
    #[command(
        long_about = "Serve the world to TCP clients (docs/protocol.md).\n\n\
                      Prints one line `listening on ADDRESS:PORT` to stdout once it accepts \
                      connections, then logs to stderr (RUST_LOG sets the level, default info). \
                      Every client gets a Hello, then every published WorldState; commands from \
                      any client are checked on arrival and applied at the next step boundary. \
                      Stops cleanly on SIGINT (Ctrl-C) or SIGTERM.",
        after_help = "Examples:\n  \
            pushlearn-sim                                   realtime, 127.0.0.1:11345\n  \
            pushlearn-sim serve --mode lockstep --port 0    lock-step on a free port\n  \
            pushlearn-sim serve --mode lockstep --latency-max 2 --latency-seed 7\n  \
            pushlearn-sim serve --mode lockstep --engine mujoco"
    )]
    Serve(ServeArgs),
    /// Run the calibration sweep: the push (0, 0.5) m/s from 21 starts x0 = -0.35 … 0.35,
    /// 150 messages at 100 Hz each, and report the blue block's outcome.
    #[command(
        long_about = "Run the thesis's calibration sweep (docs/spec/world.md §10).\n\n\
                      For each start x0 = -0.35 + 0.035·i (i = 0…20): reset, place the actuator at \
                      (x0, 0, 0.03), command Move (0, 0.5) m/s, step 150 messages at 100 Hz \
                      (1500 steps of 1 ms), and report the blue block (blockA): the first message \
                      whose interval contained an actuator–block contact, its final x, y and yaw, \
                      its translation from the start and its rotation."
    )]
    Sweep(SweepArgs),
    /// Serve a recording (`pushlearn ctl record`) to clients as if it were the world.
    #[command(
        long_about = "Serve a recording made by `pushlearn ctl record` to clients as if it were \
                      the world (docs/protocol.md §9).\n\n\
                      Every client gets the recorded Hello, then the recorded states: in a \
                      lock-step recording one per Advance, otherwise at their recorded pace (or at \
                      once with --fast). Commands are answered as the world answered the recorded \
                      ones; where they differ from the recorded commands they are counted and \
                      logged (once per kind), so you can see that a learner diverged from the \
                      recording. At the end of the recording the connection is closed (a further \
                      Advance is answered with an Error saying so). Prints `listening on \
                      ADDRESS:PORT` like serve; stops on SIGINT or SIGTERM.",
        after_help = "Examples:\n  \
            pushlearn ctl record run.plrec --listen 127.0.0.1:12000   # then a learner on :12000\n  \
            pushlearn-sim replay run.plrec --listen 127.0.0.1:0"
    )]
    Replay(ReplayArgs),
    /// Scene files: generate objects nobody has seen.
    #[command(subcommand)]
    Scene(SceneCmd),
}

#[derive(Debug, Subcommand)]
enum SceneCmd {
    /// Draw objects from seeded distributions and write one scene file per object.
    #[command(
        long_about = "Draw objects from seeded distributions (docs/world.md \"Generated objects\", \
                      with the sources of every range) and write one scene file per object, \
                      DIR/SET-000.toml, DIR/SET-001.toml, …, and DIR/SET-index.json listing the \
                      values drawn.\n\n\
                      Each scene is the push task's world (one_block: ground, physics, drive and \
                      actuator unchanged) with one object in place of the blue block, under its \
                      name and id (blockA, 15) and at its start (0, 0.25), so that every experiment \
                      and learner runs it: `pushlearn-sim serve --scene DIR/test-000.toml`.\n\n\
                      Every value is uniform on its range and independent of the others:\n  \
                      box           width (across the push, x) 0.1–0.5 m, depth (along it, y) 0.1–0.3 m\n  \
                      cylinder      radius 0.05–0.15 m (held-out set only)\n  \
                      height        0.06–0.1 m (above the pusher's top, 0.055 m; never taller than wide)\n  \
                      mass          0.5–2 kg\n  \
                      centre of mass  offset ±0.5 of the way to the side (box: x and y each; cylinder: \
                      radius fraction at a uniform angle), at mid-height; inertia: the uniform solid's \
                      about the centre of mass\n  \
                      friction      object–ground 0.1–0.3, object–pusher 0.1–0.5 (isotropic, [[friction]] tables)\n\n\
                      Sets: train and test are boxes from disjoint streams; held-out is cylinders, a \
                      shape family no training or test object belongs to. Object i of a set depends \
                      only on the seed, the set and i: a larger --count adds objects, it changes none.",
        after_help = "Examples:\n  \
            pushlearn-sim scene generate --set train --count 100 --seed 1 --out objects/\n  \
            pushlearn-sim scene generate --set test --count 50 --seed 1 --out objects/\n  \
            pushlearn-sim scene generate --set held-out --count 20 --seed 1 --out objects/"
    )]
    Generate(GenerateArgs),
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum SetArg {
    /// Boxes, for training and tuning.
    Train,
    /// Boxes from another stream than train's.
    Test,
    /// Cylinders: the shape family no train or test object belongs to.
    HeldOut,
}

#[derive(Debug, Args)]
struct GenerateArgs {
    /// Which objects to draw.
    #[arg(long, value_enum)]
    set: SetArg,
    /// How many objects, 1 to 10000 (one file each).
    #[arg(long, value_name = "N",
          value_parser = clap::value_parser!(u64).range(1..=10_000).map(|n| n as usize))]
    count: usize,
    /// Seed of the generators (with the set and the object's index).
    #[arg(long, value_name = "S", default_value_t = 0)]
    seed: u64,
    /// Directory the scene files go to (created if missing; files of the same names are
    /// replaced).
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
}

#[derive(Debug, Args)]
struct ReplayArgs {
    /// The recording.
    file: PathBuf,
    /// Address to listen on; port 0 picks a free one (read it from the `listening on` line).
    #[arg(long, value_name = "HOST:PORT", default_value = "127.0.0.1:11345")]
    listen: SocketAddr,
    /// Serve a realtime recording as fast as the client reads, without its recorded pauses.
    #[arg(long)]
    fast: bool,
    /// Clients served at once; one more gets an `Error` and is closed.
    #[arg(long, value_name = "N", default_value_t = DEFAULT_MAX_CLIENTS,
          value_parser = clap::value_parser!(u64).range(1..).map(|n| n as usize))]
    max_clients: usize,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum Mode {
    /// Step continuously, paced by --real-time-rate (the thesis's setting).
    Realtime,
    /// After each publish, wait for a client's Advance (reproducible runs).
    Lockstep,
}

#[derive(Debug, Args)]
struct ServeArgs {
    /// Built-in scene name (`one_block`, `two_blocks`, `objects`) or path to a scene TOML file.
    #[arg(long, value_name = "NAME_OR_FILE", default_value = DEFAULT_SCENE)]
    scene: String,
    /// Address to listen on. Anything but a loopback address exposes an
    /// unauthenticated control port to the network.
    #[arg(long, value_name = "ADDR", default_value = "127.0.0.1")]
    bind: IpAddr,
    /// TCP port; 0 picks a free one (read it from the `listening on` line).
    #[arg(long, value_name = "P", default_value_t = DEFAULT_PORT)]
    port: u16,
    /// Timing mode (docs/protocol.md §5).
    #[arg(long, value_enum, default_value_t = Mode::Realtime)]
    mode: Mode,
    /// Realtime mode: physics steps of 1 ms per wall-clock second (500 = real-time
    /// factor 0.5, as in the thesis); 0 steps as fast as possible.
    #[arg(long, value_name = "STEPS_PER_S", default_value_t = DEFAULT_REAL_TIME_RATE)]
    real_time_rate: u32,
    /// World states per simulated second; must divide 1000 (the thesis used 100
    /// and 10). [default: the scene's, 100 for the built-in scenes]
    #[arg(long, value_name = "HZ")]
    rate: Option<u32>,
    /// Lock-step latency emulation: each Move takes effect after a uniformly
    /// drawn 0..=L steps of the next interval (`pushlearn experiment` uses 2,
    /// derived from the thesis's timing in docs/spec/world.md §8). Off unless
    /// given; needs --mode lockstep.
    #[arg(long, value_name = "L")]
    latency_max: Option<u32>,
    /// Seed of the latency emulation's generator (clients can reseed it with
    /// the latency_seed command). [default: 0]
    #[arg(long, value_name = "S", requires = "latency_max")]
    latency_seed: Option<u64>,
    /// Clients served at once; one more gets an Error and is closed.
    #[arg(long, value_name = "N", default_value_t = DEFAULT_MAX_CLIENTS)]
    max_clients: usize,
    /// Messages each client's outgoing queue holds; when it is full the oldest
    /// state is dropped (and counted).
    #[arg(long, value_name = "N", default_value_t = DEFAULT_CLIENT_QUEUE)]
    client_queue: usize,
    /// A client whose queue stays full this long is disconnected.
    #[arg(long, value_name = "SECONDS", default_value = "5", value_parser = parse_seconds)]
    slow_client_timeout: Duration,
    /// A client over which nothing has passed for this long — no frame from
    /// it, no frame written to it (a lock-step world nobody advances, a
    /// paused one, or a client that stopped reading) — is disconnected, so
    /// that silent connections cannot hold every place.
    #[arg(long, value_name = "SECONDS", default_value = "60", value_parser = parse_seconds)]
    idle_timeout: Duration,
    /// Stop, as on SIGTERM, when standard input reaches its end: a program
    /// that starts the world with a pipe as its stdin (the Python package's
    /// Gymnasium environments do) then takes it down with itself, even when
    /// it is killed with SIGKILL and cannot stop it.
    #[arg(long)]
    stop_with_stdin: bool,
    /// Physics engine: `ode` (the thesis's, every published number) or `mujoco` (the
    /// held-out engine, docs/world.md "Two engines"; the Hello names it).
    #[arg(long, value_name = "ENGINE", default_value_t = Engine::Ode)]
    engine: Engine,
}

fn parse_seconds(text: &str) -> Result<Duration, String> {
    pushlearn::duration::parse_positive_seconds(text)
        .map_err(|_| format!("expected a positive number of seconds, found '{text}'"))
}

#[derive(Debug, Args)]
struct SweepArgs {
    /// Built-in scene name (`one_block`, `two_blocks`, `objects`) or path to a scene TOML file.
    #[arg(long, value_name = "NAME_OR_FILE", default_value = DEFAULT_SCENE)]
    scene: String,
    /// Print a JSON array of objects with the keys x0, first_contact_message, block_x,
    /// block_y, block_yaw, translation, rotation (metres, radians) instead of a table.
    #[arg(long)]
    json: bool,
    /// The body pushed [default: the blue block, `blockA`]; another body takes the blue
    /// block's start for every run and the blue block its place (e.g. `--scene objects
    /// --body cylinder`, docs/world.md "New objects").
    #[arg(long, value_name = "NAME", default_value = sim_plugin::calibration::BLUE_BLOCK)]
    body: String,
    /// Physics engine: `ode` (the thesis's, every published number) or `mujoco` (the
    /// held-out engine, docs/world.md "Two engines").
    #[arg(long, value_name = "ENGINE", default_value_t = Engine::Ode)]
    engine: Engine,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    // A daemon reports its clients coming and going; a one-shot command only
    // its problems.
    let default_level = match cli.command {
        None | Some(Cmd::Serve(_)) => "info",
        Some(Cmd::Sweep(_)) => "warn",
        Some(Cmd::Replay(_)) => "info",
        Some(Cmd::Scene(_)) => "warn",
    };
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env()
                .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new(default_level)),
        )
        .with_writer(std::io::stderr)
        .with_ansi(pushlearn::errors::colours())
        .init();
    let result = match cli.command {
        None => run_serve(&cli.serve),
        Some(Cmd::Serve(args)) => run_serve(&args),
        Some(Cmd::Sweep(args)) => run_sweep(&args),
        Some(Cmd::Replay(args)) => run_replay(&args),
        Some(Cmd::Scene(SceneCmd::Generate(args))) => run_generate(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) => {
            eprintln!("{}", pushlearn::errors::describe(err.as_ref()));
            ExitCode::FAILURE
        }
    }
}

fn serve_config(args: &ServeArgs) -> anyhow::Result<Config> {
    let scene =
        Scene::load(&args.scene).with_context(|| format!("loading scene `{}`", args.scene))?;
    let timing = match (args.mode, args.latency_max) {
        (Mode::Realtime, Some(_)) => {
            bail!("--latency-max emulates latency in lock-step mode; add --mode lockstep")
        }
        (Mode::Realtime, None) => Timing::Realtime {
            steps_per_second: args.real_time_rate,
        },
        (Mode::Lockstep, latency) => Timing::Lockstep {
            latency: latency.map(|max_steps| Latency {
                max_steps,
                seed: args.latency_seed.unwrap_or(0),
            }),
        },
    };
    Ok(Config {
        timing,
        publish_rate_hz: args.rate,
        max_clients: args.max_clients,
        client_queue: args.client_queue,
        slow_client_limit: args.slow_client_timeout,
        idle_limit: args.idle_timeout,
        engine: args.engine,
        ..Config::new(scene)
    })
}

fn run_serve(args: &ServeArgs) -> anyhow::Result<()> {
    let config = serve_config(args)?;
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()
        .context("cannot start the async runtime")?;
    runtime.block_on(async {
        let listener = tokio::net::TcpListener::bind((args.bind, args.port))
            .await
            .with_context(|| format!("cannot listen on {}:{}", args.bind, args.port))?;
        let server = Server::start(listener, config).await?;
        // Handlers go in before the line below: whoever reads it may signal
        // at once, and an uninstalled SIGTERM would kill us uncleanly.
        let shutdown = shutdown_signal()?;
        let stdin_closed = stdin_closed(args.stop_with_stdin);
        // The one line on stdout, for scripts and tests that start the daemon
        // on port 0 and need to know where it is.
        let mut out = std::io::stdout().lock();
        writeln!(out, "listening on {}", server.local_addr())?;
        out.flush()?;
        drop(out);
        tokio::select! {
            () = shutdown => {
                tracing::info!("shutting down");
            }
            () = stdin_closed => {
                tracing::info!("standard input closed: shutting down");
            }
            () = server.stopped() => {}
        }
        server.shutdown().await?;
        Ok(())
    })
}

/// The future that completes once standard input reaches its end (or fails),
/// if `watch`; else one that never does. A plain thread reads it: tokio's
/// stdin reads on a blocking-pool thread that would hold the runtime's
/// shutdown until the read returned.
fn stdin_closed(watch: bool) -> impl std::future::Future<Output = ()> {
    let on_close = watch.then(|| {
        let (closed, on_close) = tokio::sync::oneshot::channel::<()>();
        std::thread::spawn(move || {
            use std::io::Read;
            let mut sink = [0u8; 256];
            let mut stdin = std::io::stdin().lock();
            loop {
                match stdin.read(&mut sink) {
                    Ok(0) => break,
                    Ok(_) => {}
                    Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                    Err(_) => break,
                }
            }
            let _ = closed.send(());
        });
        on_close
    });
    async move {
        match on_close {
            Some(on_close) => {
                let _ = on_close.await;
            }
            None => std::future::pending::<()>().await,
        }
    }
}

/// Installs the SIGINT (Ctrl-C) and SIGTERM handlers now and returns the
/// future that completes on the first of them.
#[cfg(unix)]
fn shutdown_signal() -> anyhow::Result<impl std::future::Future<Output = ()>> {
    use tokio::signal::unix::{signal, SignalKind};
    let mut interrupt = signal(SignalKind::interrupt()).context("cannot listen for SIGINT")?;
    let mut terminate = signal(SignalKind::terminate()).context("cannot listen for SIGTERM")?;
    Ok(async move {
        tokio::select! {
            _ = interrupt.recv() => {}
            _ = terminate.recv() => {}
        }
    })
}

/// The Ctrl-C future (installed on its first poll, right after start-up).
#[cfg(not(unix))]
fn shutdown_signal() -> anyhow::Result<impl std::future::Future<Output = ()>> {
    Ok(async {
        if let Err(e) = tokio::signal::ctrl_c().await {
            tracing::error!("cannot listen for Ctrl-C: {e}");
            std::future::pending::<()>().await;
        }
    })
}

fn run_replay(args: &ReplayArgs) -> anyhow::Result<()> {
    let name = args.file.display().to_string();
    let recording = pushlearn::recording::read_file(&args.file)?;
    if let Some(cut) = recording.truncated {
        tracing::warn!(
            "{name} ends inside a record (byte {}, {} bytes of it): replaying the {} whole records before it",
            cut.offset,
            cut.present,
            recording.records.len()
        );
    }
    let replay = Replay::new(recording, name.clone(), args.fast);
    tracing::info!("{name}: {} states", replay.states());
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()
        .context("cannot start the async runtime")?;
    runtime.block_on(async {
        let listener = tokio::net::TcpListener::bind(args.listen)
            .await
            .with_context(|| format!("cannot listen on {}", args.listen))?;
        let shutdown = shutdown_signal()?;
        let mut out = std::io::stdout().lock();
        writeln!(out, "listening on {}", listener.local_addr()?)?;
        out.flush()?;
        drop(out);
        tokio::select! {
            () = shutdown => tracing::info!("shutting down"),
            served = Arc::new(replay).serve(listener, args.max_clients) => served.context("accepting clients")?,
        }
        Ok(())
    })
}

fn run_generate(args: &GenerateArgs) -> anyhow::Result<()> {
    use sim_plugin::generate::{generate, Distributions, Set};
    let set = match args.set {
        SetArg::Train => Set::Train,
        SetArg::Test => Set::Test,
        SetArg::HeldOut => Set::HeldOut,
    };
    let dist = Distributions::default();
    let objects = generate(set, args.count, args.seed, &dist).context("drawing the objects")?;
    let out = &args.out;
    std::fs::create_dir_all(out)
        .with_context(|| format!("--out: cannot create the directory {}", out.display()))?;
    let write = |name: String, text: String| {
        let path = out.join(name);
        std::fs::write(&path, text)
            .with_context(|| format!("--out: cannot write {}", path.display()))
    };
    let command = format!(
        "pushlearn-sim scene generate --set {set} --count {} --seed {}",
        args.count, args.seed
    );
    for (i, g) in objects.iter().enumerate() {
        let toml = g
            .scene
            .to_toml_string()
            .with_context(|| format!("writing object {i} as TOML"))?;
        write(
            format!("{}.toml", g.object.name),
            format!("# Object {i} of `{command}` (docs/world.md \"Generated objects\").\n{toml}"),
        )?;
    }
    let index = serde_json::json!({
        "command": command,
        "set": set,
        "seed": args.seed,
        "distributions": dist,
        "objects": objects.iter().map(|g| &g.object).collect::<Vec<_>>(),
    });
    write(
        format!("{set}-index.json"),
        format!("{}\n", serde_json::to_string_pretty(&index)?),
    )?;
    println!(
        "wrote {} scene files and {set}-index.json to {}",
        objects.len(),
        out.display()
    );
    Ok(())
}

fn run_sweep(args: &SweepArgs) -> anyhow::Result<()> {
    let scene =
        Scene::load(&args.scene).with_context(|| format!("loading scene `{}`", args.scene))?;
    tracing::info!(scene = %scene.name, "running the calibration sweep");
    let options = SweepOptions {
        body: args.body.clone(),
        engine: args.engine,
        ..SweepOptions::default()
    };
    let rows = sim_plugin::sweep(&scene, &options).context("running the sweep")?;
    let mut out = std::io::stdout().lock();
    if args.json {
        serde_json::to_writer_pretty(&mut out, &rows)?;
        writeln!(out)?;
    } else {
        write_table(&mut out, &scene.name, &args.body, args.engine, &rows)?;
    }
    Ok(())
}

fn write_table(
    out: &mut impl Write,
    scene: &str,
    body: &str,
    engine: Engine,
    rows: &[SweepRow],
) -> std::io::Result<()> {
    writeln!(
        out,
        "calibration sweep, scene {scene}: push (0, 0.5) m/s, 150 messages at 100 Hz; body {body}; engine {engine}"
    )?;
    writeln!(
        out,
        "{:>7}  {:>13}  {:>8}  {:>8}  {:>9}  {:>11}  {:>9}",
        "x0", "first contact", "x", "y", "yaw", "translation", "rotation"
    )?;
    for r in rows {
        let contact = r
            .first_contact_message
            .map_or_else(|| "-".to_owned(), |m| m.to_string());
        writeln!(
            out,
            "{:>7.3}  {:>13}  {:>8.4}  {:>8.4}  {:>9.4}  {:>11.4}  {:>9.4}",
            r.x0, contact, r.block_x, r.block_y, r.block_yaw, r.translation, r.rotation
        )?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;
    use sim_plugin::generate::Distributions;

    /// `scene generate --help` spells the default ranges out for a reader;
    /// this keeps the text equal to what the generator draws from.
    #[test]
    fn the_generate_help_states_the_default_ranges() {
        let mut cli = Cli::command();
        let help = cli
            .find_subcommand_mut("scene")
            .and_then(|scene| scene.find_subcommand_mut("generate"))
            .map(|generate| generate.render_long_help().to_string())
            .unwrap_or_default();
        let d = Distributions::default();
        for (what, range) in [
            ("box width", d.box_width),
            ("box depth", d.box_depth),
            ("cylinder radius", d.cylinder_radius),
            ("height", d.height),
            ("mass", d.mass),
            ("object–ground friction", d.ground_friction),
            ("object–pusher friction", d.pusher_friction),
        ] {
            let text = format!("{}–{}", range.lo, range.hi);
            assert!(help.contains(&text), "{what}: {text} is not in:\n{help}");
        }
        let com = format!("±{}", d.com_fraction.hi);
        assert_eq!(d.com_fraction.lo, -d.com_fraction.hi);
        assert!(
            help.contains(&com),
            "centre of mass: {com} is not in:\n{help}"
        );
    }
}
