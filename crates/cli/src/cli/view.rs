//! `pushlearn view`: the browser viewer.

use std::io::Write;
use std::net::{IpAddr, Ipv4Addr, SocketAddr};

use anyhow::{Context, Result};
use clap::builder::TypedValueParser as _;
use clap::Args;
use pushlearn::client::{ClientOptions, SimClient, DEFAULT_ADDR};
use pushlearn_cli::view::{Viewer, DEFAULT_MAX_CONNECTIONS, DEFAULT_PORT};

/// Watch a running world (pushlearn-sim) live in the browser: a top-down
/// view of every body, the learner's predictions and target, the simulated
/// time, and buttons to pause, unpause and reset the world.
///
/// Prints one line `viewer on http://ADDRESS:PORT/` to stdout; open it in a
/// browser. Bodies are drawn opaque, a learner's predictions (`pushlearn
/// learn --shadows`) translucent, a Move-to-Target goal as a dashed outline.
/// The viewer is an ordinary client of the world: start it before or after
/// the learner; if the world goes away it reconnects every second. Stop
/// with Ctrl-C. More: docs/viewer.md.
#[derive(Debug, Args)]
#[command(after_help = "Examples:\n  \
    pushlearn view                                  the world on 127.0.0.1:11345, page on port 11346\n  \
    pushlearn view --sim 127.0.0.1:40000 --port 0   another world, page on a free port")]
pub struct ViewArgs {
    /// Address of the world daemon.
    #[arg(long, alias = "connect", value_name = "HOST:PORT", default_value = DEFAULT_ADDR)]
    sim: String,

    /// Port of the page; 0 picks a free one (read it from the `viewer on` line).
    #[arg(long, value_name = "P", default_value_t = DEFAULT_PORT)]
    port: u16,

    /// Address to serve the page on. Anything but a loopback address lets
    /// everyone who can reach it pause and reset the world.
    #[arg(long, value_name = "ADDR", default_value_t = IpAddr::V4(Ipv4Addr::LOCALHOST))]
    bind: IpAddr,

    /// The most browser connections served at once (page loads and open
    /// tabs); one more is answered `503 Service Unavailable`.
    #[arg(long, value_name = "N", default_value_t = DEFAULT_MAX_CONNECTIONS,
          value_parser = clap::value_parser!(u64).range(1..).map(|n| n as usize))]
    max_connections: usize,
}

/// Runs `pushlearn view`.
pub fn run(args: ViewArgs) -> Result<()> {
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .context("cannot start the async runtime")?;
    runtime.block_on(async {
        // A wrong --sim is reported now rather than as a page that stays empty.
        let world = SimClient::connect_with(args.sim.as_str(), ClientOptions::clock_seqs())
            .await
            .map_err(|err| {
                anyhow::anyhow!(
                    "{err}; is pushlearn-sim running? (start it with `pushlearn-sim serve`, \
                     or point --sim at it)"
                )
            })?;
        let viewer = Viewer::bind(SocketAddr::new(args.bind, args.port))
            .await?
            .with_max_connections(args.max_connections);
        if !args.bind.is_loopback() {
            tracing::warn!(
                bind = %args.bind,
                "the viewer is reachable from the network: anyone who can reach it can pause and reset the world"
            );
        }
        let hello = world.hello();
        eprintln!(
            "pushlearn view: world {} (scene {}, {}, {} Hz); Ctrl-C to stop",
            args.sim, hello.scene, hello.timing_mode, hello.publish_rate
        );
        // The one line on stdout, for people and for scripts on port 0.
        let mut out = std::io::stdout().lock();
        writeln!(out, "viewer on {}", viewer.url())?;
        out.flush()?;
        drop(out);
        let interrupted = async {
            if let Err(err) = tokio::signal::ctrl_c().await {
                tracing::warn!(%err, "cannot listen for Ctrl-C");
                std::future::pending::<()>().await;
            }
        };
        viewer.run(world, args.sim.clone(), interrupted).await;
        Ok(())
    })
}
