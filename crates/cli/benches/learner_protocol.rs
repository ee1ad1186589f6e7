//! The learner protocol's cost per world message (docs/performance.md §7):
//! one Update and one Predict, the driver's calls on every training message,
//! on the trivial `still` reference (learner::StillModel: nothing moves), once
//! in-process and once behind the protocol — a child on stdin/stdout (this
//! benchmark's own executable, started as the learner) and a learner daemon
//! on loopback TCP. The difference is what the protocol adds.

use std::hint::black_box;
use std::net::TcpListener;
use std::time::Duration;

use criterion::Criterion;
use learner::{Action, Frame, Model, StillModel};
use pushlearn_cli::external::check::scripted_state;
use pushlearn_cli::external::server::{serve, Identity, Requests};
use pushlearn_cli::external::{ExternalModel, LearnerSpec, Source};

/// Set in the child this benchmark starts as its learner.
const AS_LEARNER: &str = "PUSHLEARN_BENCH_AS_LEARNER";

fn identity() -> Identity {
    Identity {
        name: "still".into(),
        version: "bench".into(),
    }
}

/// Serves [`StillModel`] to one driver on `input`/`output`.
fn serve_still(input: impl std::io::Read, output: impl std::io::Write) {
    let mut requests = Requests::new(input);
    if let Ok((seq, _)) = requests.start() {
        let _ = serve(StillModel::default(), &identity(), seq, requests, output);
    }
}

/// A world message as the world sends it: the actuator and the blue block.
fn frame(y: f64) -> Frame {
    scripted_state((0.0, y), (0.0, 0.25))
}

/// One training message: parse, update, predict.
fn message<M: Model>(model: &mut M, frame: &Frame) -> M::World {
    let world = model.parse(frame).expect("parses");
    model.update(&world, Action::new(0.0, 0.5));
    model.predict(&world, Action::new(0.0, 0.5))
}

fn bench_external(c: &mut Criterion, name: &str, source: Source) {
    let spec = LearnerSpec {
        source,
        timeout: Duration::from_secs(10),
    };
    let mut model = ExternalModel::connect(&spec, "push-task", 100).expect("the learner starts");
    model.start_fold(1);
    let f = frame(0.1);
    model.reset_objects(&model.parse(&f).expect("parses"));
    c.bench_function(name, |b| {
        b.iter(|| black_box(message(&mut model, &f)));
    });
    assert!(model.failure().is_none(), "{:?}", model.failure());
}

fn main() {
    if std::env::var_os(AS_LEARNER).is_some() {
        let stdout = pushlearn_cli::external::server::stdout_file().expect("stdout");
        serve_still(std::io::stdin().lock(), std::io::BufWriter::new(stdout));
        return;
    }
    // Without plots: criterion's plotters backend needs a system font.
    let mut c = Criterion::default().without_plots().configure_from_args();
    let f = frame(0.1);
    let mut still = StillModel::default();
    c.bench_function("message/in-process", |b| {
        b.iter(|| black_box(message(&mut still, &f)));
    });

    let exe = std::env::current_exe().expect("the benchmark's own path");
    let command = format!("{AS_LEARNER}=1 '{}'", exe.display());
    bench_external(
        &mut c,
        "message/child stdin-stdout",
        Source::Command(command),
    );

    let listener = TcpListener::bind("127.0.0.1:0").expect("a loopback port");
    let addr = listener.local_addr().expect("bound").to_string();
    std::thread::spawn(move || {
        for stream in listener.incoming().flatten() {
            let _ = stream.set_nodelay(true);
            if let Ok(reader) = stream.try_clone() {
                std::thread::spawn(move || serve_still(reader, std::io::BufWriter::new(stream)));
            }
        }
    });
    bench_external(&mut c, "message/daemon tcp", Source::Connect(addr));
    c.final_summary();
}
