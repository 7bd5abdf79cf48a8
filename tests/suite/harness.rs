//! The test harness itself: tests that share the machine never stall one another, and
//! one failure leaves every other test to finish and report.

use crate::common::{self, Machine};
use std::sync::mpsc;
use std::time::Duration;

/// A thread that holds a machine shared and asks for it again while another test waits
/// to hold it alone gets its hold at once (the same hold), and the waiting test runs
/// once it is released. (With std's `RwLock` taken twice, the second read queues behind
/// the waiting writer and neither thread moves: the first GPU run's stalled suite.) The
/// machine is the test's own, so a failure here stalls no other test.
#[test]
fn a_test_asking_again_while_another_waits_alone_does_not_stall() {
    static OWN: Machine = Machine::new();
    let (done, finished) = mpsc::channel();
    std::thread::spawn(move || {
        let first = OWN.share().expect("a shared hold");
        let (queued, waiting) = mpsc::channel();
        let (got, got_alone) = mpsc::channel();
        let writer = std::thread::spawn(move || {
            queued.send(()).unwrap();
            let _alone = OWN.alone();
            got.send(()).unwrap();
        });
        waiting.recv().unwrap();
        // The writer is queued behind this thread's hold by now.
        std::thread::sleep(Duration::from_millis(300));
        assert!(
            got_alone.try_recv().is_err(),
            "alone() while the machine was held shared"
        );
        let again = OWN.share().expect("a shared hold");
        assert!(std::rc::Rc::ptr_eq(&first, &again), "one hold a thread");
        drop((first, again));
        got_alone
            .recv_timeout(Duration::from_secs(20))
            .expect("the waiting test runs after");
        writer.join().unwrap();
        done.send(()).unwrap();
    });
    finished
        .recv_timeout(Duration::from_secs(30))
        .expect("the second shared hold stalled behind the waiting alone()");
}

/// A test that holds the machine alone gets no shared hold for what it starts (it has
/// the machine already), and asking to hold it alone while holding it shared fails the
/// test at once instead of waiting for itself.
#[test]
fn alone_and_shared_holds_do_not_wait_for_themselves() {
    static OWN: Machine = Machine::new();
    {
        let _alone = OWN.alone();
        assert!(OWN.share().is_none());
    }
    let _share = OWN.share().expect("a shared hold once alone has ended");
    let asked = std::panic::catch_unwind(|| {
        let _alone = OWN.alone();
    });
    assert!(
        asked.is_err(),
        "alone() under this thread's own shared hold must fail, not wait"
    );
}

/// Fails on purpose, holding a GPU context and a run of the binary as the first GPU
/// run's failing tests did, when `SPECULUM_TEST_FAIL_ON_PURPOSE` is set (CI does not set
/// it; `tools/gpu-check` does once, to show a failure stalls nothing): the suite then
/// reports this one failure and every other test's result.
#[test]
fn fails_on_purpose_when_asked() {
    if std::env::var_os("SPECULUM_TEST_FAIL_ON_PURPOSE").is_none() {
        return;
    }
    let _ctx = common::context();
    let out = common::speculum(["devices"]).run();
    assert!(out.ok(), "{}", out.stderr);
    panic!("failed on purpose (SPECULUM_TEST_FAIL_ON_PURPOSE is set)");
}

/// `tools/gpu-check`'s smoke step, alone: with a device name that matches nothing it
/// stops within seconds, exit 1, and its summary says so with the device list and the
/// loader's own lines; with the test's device it renders a frame and passes.
#[test]
fn the_gpu_checks_smoke_step_stops_early_with_the_loaders_reason() {
    let _share = common::hold_shared();
    let dir = tempfile::tempdir().unwrap();
    let smoke = |device: &str| {
        let out = dir.path().join(device);
        let start = std::time::Instant::now();
        let status = std::process::Command::new("timeout")
            .args([
                "120",
                "tools/gpu-check",
                "smoke",
                env!("CARGO_BIN_EXE_speculum"),
                device,
            ])
            .arg(&out)
            .status()
            .expect("runs tools/gpu-check");
        let summary = std::fs::read_to_string(out.join("summary.md")).unwrap_or_default();
        (status.code(), summary, start.elapsed())
    };
    let (code, summary, took) = smoke("no-such-gpu-xyz");
    assert_eq!(code, Some(1), "{summary}");
    assert!(
        summary.contains("smoke: FAILED") && summary.contains("VK_LOADER_DEBUG=driver"),
        "{summary}"
    );
    assert!(took < Duration::from_secs(60), "took {took:?}");
    let device = std::env::var("SPECULUM_TEST_DEVICE").unwrap_or_else(|_| {
        let list = speculum::vk::list_devices().unwrap();
        list.into_iter()
            .find(|d| d.usable.is_ok())
            .expect("a usable device")
            .name
    });
    let (code, summary, _) = smoke(&device);
    assert_eq!(code, Some(0), "{summary}");
    assert!(summary.contains("one frame rendered"), "{summary}");
}
