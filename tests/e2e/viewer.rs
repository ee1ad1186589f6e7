//! `pushlearn view` in a real browser (headless Chromium): the page draws the
//! bodies where the world says they are, and its buttons control the world.
//!
//! The world runs in lock-step, so nothing moves unless this test advances
//! it: every state the page must show is known exactly, and "paused" can be
//! checked without timing (a paused lock-step world refuses Advance).

use std::path::PathBuf;
use std::process::Command;
use std::time::Duration;

use pushlearn::client::{ClientError, SimClient};
use pushlearn::wire::pb::{self, client_message::Payload};
use serde_json::Value;

use crate::browser::Browser;
use crate::daemon::Daemon;
use crate::process::Background;

/// How long the page may take to show something.
const SHOW_LIMIT: Duration = Duration::from_secs(20);

/// The page's state, printed when a wait fails.
const REPORT: &str = "JSON.stringify({view: window.pushlearnView || null, \
    status: (document.getElementById('status') || {}).textContent, \
    message: (document.getElementById('message') || {}).textContent})";

/// Colours the page fills with (crates/cli/src/view/page.html), and its background.
const BLUE: [f64; 3] = [31.0, 95.0, 208.0];
const GREY: [f64; 3] = [68.0, 68.0, 68.0];
const BACKGROUND: [f64; 3] = [247.0, 247.0, 242.0];
const SHADOW_ALPHA: f64 = 0.35;

/// A running `pushlearn view --port 0`.
struct Viewer {
    url: String,
    _process: Background,
}

impl Viewer {
    fn start(world: std::net::SocketAddr) -> Viewer {
        let mut command = Command::new(env!("CARGO_BIN_EXE_pushlearn"));
        command
            .args(["view", "--port", "0", "--sim"])
            .arg(world.to_string());
        let (mut process, line) = Background::start(command, "pushlearn view");
        match line.trim_end().strip_prefix("viewer on ") {
            Some(url) if url.starts_with("http://127.0.0.1:") => Viewer {
                url: url.to_owned(),
                _process: process,
            },
            _ => panic!(
                "pushlearn view did not print its address (first line {line:?}); its log:\n{}",
                process.stop()
            ),
        }
    }
}

fn pose(state: &pb::WorldState, name: &str) -> (f64, f64, f64) {
    let model = state
        .model(name)
        .unwrap_or_else(|| panic!("the world published no {name}: {state:?}"));
    let pose = model.pose.unwrap_or_default();
    let p = pose.position.unwrap_or_default();
    (p.x, p.y, pose.orientation.unwrap_or_default().yaw())
}

/// The entry for `name` in the page's last drawn frame.
fn drawn<'a>(frame: &'a Value, name: &str) -> &'a Value {
    frame
        .as_array()
        .and_then(|bodies| bodies.iter().find(|b| b["name"] == name))
        .unwrap_or_else(|| panic!("the page did not draw {name}: {frame}"))
}

fn assert_drawn_at(frame: &Value, name: &str, kind: &str, (x, y, yaw): (f64, f64, f64)) {
    let body = drawn(frame, name);
    assert_eq!(body["kind"], kind, "{body}");
    let got = [&body["x"], &body["y"], &body["yaw"]].map(|v| v.as_f64().unwrap_or(f64::NAN));
    for (got, want) in got.into_iter().zip([x, y, yaw]) {
        assert!(
            (got - want).abs() < 1e-9,
            "{name} drawn at {body}, the world says ({x}, {y}, {yaw})"
        );
    }
}

/// The canvas pixel (RGB) at world point (x, y), through the page's own
/// world-to-canvas transform.
async fn pixel(browser: &mut Browser, x: f64, y: f64) -> [f64; 3] {
    let value = browser
        .eval(&format!(
            "(() => {{ const [px, py] = pushlearnView.toScreen({x}, {y}); \
             const c = document.getElementById('view'); \
             return Array.from(c.getContext('2d').getImageData(Math.round(px), Math.round(py), 1, 1).data); }})()"
        ))
        .await;
    let rgba: Vec<f64> = value
        .as_array()
        .map(|v| v.iter().filter_map(Value::as_f64).collect())
        .unwrap_or_default();
    assert_eq!(rgba.len(), 4, "getImageData gave {value}");
    [rgba[0], rgba[1], rgba[2]]
}

fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(a, b)| (a - b).powi(2))
        .sum::<f64>()
        .sqrt()
}

fn blend(colour: [f64; 3], alpha: f64, under: [f64; 3]) -> [f64; 3] {
    [0, 1, 2].map(|i| alpha * colour[i] + (1.0 - alpha) * under[i])
}

fn assert_colour(got: [f64; 3], want: [f64; 3], what: &str) {
    // Anti-aliasing and a grid line under a translucent shadow move a
    // channel by a few units; other colours are far away.
    assert!(
        distance(got, want) < 25.0,
        "{what}: the canvas has {got:?} there, expected about {want:?}"
    );
}

/// Waits until the page shows the world state `state`.
async fn wait_for_state(browser: &mut Browser, state: &pb::WorldState) -> Value {
    browser
        .wait_for(
            &format!(
                "window.pushlearnView && pushlearnView.state && \
                 pushlearnView.state.publish_seq === {}",
                state.publish_seq
            ),
            &format!("the world state with publish_seq {}", state.publish_seq),
            REPORT,
            SHOW_LIMIT,
        )
        .await;
    browser.eval("pushlearnView.lastDrawn").await
}

/// Clicks a button and waits until the world's answer reached the page.
async fn click(browser: &mut Browser, button: &str) {
    browser
        .wait_for(
            &format!("!document.getElementById('{button}').disabled"),
            &format!("an enabled {button} button"),
            REPORT,
            SHOW_LIMIT,
        )
        .await;
    browser
        .eval(&format!("document.getElementById('{button}').click()"))
        .await;
    browser
        .wait_for(
            &format!(
                "pushlearnView.lastControl && pushlearnView.lastControl.action === '{button}' \
                 && pushlearnView.lastControl.accepted"
            ),
            &format!("that the world accepted {button}"),
            REPORT,
            SHOW_LIMIT,
        )
        .await;
}

/// Where the screenshot goes: next to the test binary (target/<profile>/),
/// where it outlives the test for a look after a failure in CI.
fn screenshot_path() -> PathBuf {
    let exe = std::env::current_exe().expect("the test binary's path");
    exe.parent()
        .and_then(|deps| deps.parent())
        .expect("the test binary lives in target/<profile>/deps")
        .join("e2e-viewer.png")
}

#[tokio::test]
async fn the_page_draws_the_world_and_controls_it() {
    let daemon = Daemon::start(&["--mode", "lockstep"]);
    let mut world = SimClient::connect(daemon.addr).await.unwrap();
    let viewer = Viewer::start(daemon.addr);

    // A scene the start poses would not give: the blue block turned by
    // 100°, its prediction and a target elsewhere.
    world
        .command(Payload::set_poses([
            (
                "blockA".to_owned(),
                pb::Pose::from_position_yaw([0.33, 0.46, 0.05], 100.0_f64.to_radians()),
            ),
            (
                "blockAShadow".to_owned(),
                pb::Pose::from_position_yaw([-0.43, 0.52, 0.05], 0.0),
            ),
            (
                "blockAShadowTarget".to_owned(),
                pb::Pose::from_position_yaw([0.05, 0.93, 0.05], 0.3),
            ),
        ]))
        .await
        .unwrap();
    let state = world
        .command_and_wait_applied(Payload::advance())
        .await
        .unwrap();

    let mut browser = Browser::start(1000, 700).await;
    browser.navigate(&viewer.url).await;
    let frame = wait_for_state(&mut browser, &state).await;

    // What the page drew is what the world published.
    let block = pose(&state, "blockA");
    assert_drawn_at(&frame, "blockA", "body", block);
    assert_drawn_at(&frame, "actuator", "body", pose(&state, "actuator"));
    let shadow = pose(&state, "blockAShadow");
    assert_drawn_at(&frame, "blockAShadow", "shadow", shadow);
    assert_drawn_at(
        &frame,
        "blockAShadowTarget",
        "target",
        pose(&state, "blockAShadowTarget"),
    );
    let time = browser
        .eval("document.getElementById('time').textContent")
        .await;
    assert!(
        time.as_str()
            .is_some_and(|t| t.contains(&format!("{:.3} s", state.sim_time))),
        "the page shows {time}, the world's time is {}",
        state.sim_time
    );

    // ... and the pixels are there: 0.2 m along the block's long axis (it is
    // 0.5 × 0.1 m) is blue, 0.2 m across it is not; the prediction is a
    // translucent blue; the actuator (r = 0.025 m) is grey at its centre.
    let (x, y, yaw) = block;
    let along = pixel(&mut browser, x + 0.2 * yaw.cos(), y + 0.2 * yaw.sin()).await;
    assert_colour(along, BLUE, "0.2 m along the blue block");
    let across = pixel(&mut browser, x - 0.2 * yaw.sin(), y + 0.2 * yaw.cos()).await;
    assert!(
        distance(across, BLUE) > 100.0,
        "0.2 m across the blue block the canvas has {across:?}: the block is drawn too wide or unrotated"
    );
    let (sx, sy, _) = shadow;
    let ghost = pixel(&mut browser, sx + 0.17, sy).await;
    assert_colour(
        ghost,
        blend(BLUE, SHADOW_ALPHA, BACKGROUND),
        "inside the prediction",
    );
    let (ax, ay, _) = pose(&state, "actuator");
    assert_colour(
        pixel(&mut browser, ax, ay).await,
        GREY,
        "the actuator's centre",
    );

    let png = browser.screenshot().await;
    assert!(
        png.starts_with(b"\x89PNG\r\n\x1a\n"),
        "the screenshot is no PNG"
    );
    let path = screenshot_path();
    std::fs::write(&path, &png).unwrap();
    println!("screenshot: {}", path.display());

    // Pause: the (lock-step) world now refuses to advance.
    click(&mut browser, "pause").await;
    match world.command(Payload::advance()).await {
        Err(ClientError::Refused { message, .. }) => {
            assert!(message.contains("paused"), "{message}");
        }
        other => panic!("a world paused from the page advanced: {other:?}"),
    }
    browser
        .wait_for(
            "document.getElementById('status').textContent === 'paused'",
            "the paused status",
            REPORT,
            SHOW_LIMIT,
        )
        .await;

    // Unpause: it advances again, and the page follows.
    click(&mut browser, "unpause").await;
    let moved = world
        .command_and_wait_applied(Payload::advance())
        .await
        .unwrap();
    assert!(moved.step > state.step);
    let frame = wait_for_state(&mut browser, &moved).await;
    assert_drawn_at(&frame, "blockA", "body", pose(&moved, "blockA"));

    // Reset: the block is back at its start pose and the ghosts are gone.
    click(&mut browser, "reset").await;
    let reset = world
        .command_and_wait_applied(Payload::advance())
        .await
        .unwrap();
    assert_eq!(reset.step, 10, "one publish interval after the reset");
    let (x, y, _) = pose(&reset, "blockA");
    assert!(
        (x - 0.0).abs() < 1e-3 && (y - 0.25).abs() < 1e-3,
        "({x}, {y})"
    );
    let frame = wait_for_state(&mut browser, &reset).await;
    assert_drawn_at(&frame, "blockA", "body", pose(&reset, "blockA"));
    let kinds: Vec<&Value> = frame
        .as_array()
        .map(|b| b.iter().map(|b| &b["kind"]).collect())
        .unwrap_or_default();
    assert!(
        kinds.iter().all(|k| *k == "body"),
        "ghosts after a reset: {frame}"
    );
}

/// The README's figure is what its "Watch a push" commands show: run them
/// (the world in lock-step, so the run is exact and fast), then look at the
/// page. `PUSHLEARN_BLESS=1` writes the screenshot to docs/figures/viewer.png.
#[tokio::test]
async fn the_readme_demo_ends_with_the_block_on_its_target_in_the_viewer() {
    let daemon = Daemon::start(&["--mode", "lockstep"]);
    let viewer = Viewer::start(daemon.addr);
    let words = crate::first_hour::readme_learn_command();
    let target = words
        .iter()
        .find_map(|w| w.strip_prefix("--target="))
        .expect("the README's command gives --target=X,Y,ORI");
    let target: Vec<f64> = target
        .split(',')
        .map(|v| v.parse().expect("a number"))
        .collect();
    let mut command = Command::new(env!("CARGO_BIN_EXE_pushlearn"));
    command
        .args(&words[1..])
        .args(["--sim", &daemon.addr.to_string()]);
    let learned = crate::process::run(command);
    let stdout = crate::experiment::succeeded(&learned);
    assert!(stdout.contains("target reached: 1 of 1"), "{stdout}");

    let mut browser = Browser::start(1000, 700).await;
    browser.navigate(&viewer.url).await;
    let mut world = SimClient::connect(daemon.addr).await.unwrap();
    let state = world
        .command_and_wait_applied(Payload::advance())
        .await
        .unwrap();
    let frame = wait_for_state(&mut browser, &state).await;
    let (x, y, _) = pose(&state, "blockA");
    assert!(
        (x - target[0]).hypot(y - target[1]) < 0.02,
        "the block ended at ({x}, {y}), the target is {target:?}"
    );
    assert_drawn_at(&frame, "blockA", "body", pose(&state, "blockA"));
    assert_drawn_at(
        &frame,
        "blockAShadowTarget",
        "target",
        pose(&state, "blockAShadowTarget"),
    );
    let png = browser.screenshot().await;
    assert!(png.starts_with(b"\x89PNG\r\n\x1a\n"), "no PNG");
    let path = screenshot_path().with_file_name("e2e-demo.png");
    std::fs::write(&path, &png).unwrap();
    if std::env::var_os("PUSHLEARN_BLESS").is_some() {
        let figure = crate::process::repo_root().join("docs/figures/viewer.png");
        std::fs::write(&figure, &png).unwrap();
        println!("blessed: {}", figure.display());
    }
}
