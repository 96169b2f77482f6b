//! The transport over real shared memory: lossless streams lose nothing, domains never cross.

use std::time::{Duration, Instant};

use ipc_types::ClaimError;
use ipc_types::prelude::*;

/// Removes the domain's files from /dev/shm when the test ends; declared before the nodes,
/// so it drops after them.
struct Cleanup(Domain);

impl Drop for Cleanup {
    fn drop(&mut self) {
        let _ = self.0.remove_leftovers();
    }
}

fn unique_domain(tag: &str) -> Domain {
    let nanos = now_ns() % 1_000_000_000;
    Domain::new(&format!("t-{tag}-{}-{nanos}", std::process::id())).unwrap()
}

/// A domain of its own for one test, and the guard that cleans it up (declare it before the
/// nodes, so it drops after them).
fn scratch_domain(tag: &str) -> (Domain, Cleanup) {
    let domain = unique_domain(tag);
    let cleanup = Cleanup(domain.clone());
    (domain, cleanup)
}

/// A node that publishes scans and subscribes to them itself.
fn scans_to_self(
    domain: &Domain,
    delivery: Delivery,
) -> (
    iceoryx2::node::Node<iceoryx2::service::ipc::Service>,
    Outlet<LaserScan>,
    Inlet<LaserScan>,
) {
    let node = domain.node("both").unwrap();
    let outlet = Outlet::create(domain, &node, topic::SCAN, delivery, 0).unwrap();
    let inlet = Inlet::open(&node, topic::SCAN).unwrap();
    (node, outlet, inlet)
}

/// Publishes `count` three-beam scans numbered from 0, then the end of stream.
fn publish_scans(outlet: &Outlet<LaserScan>, count: u64) {
    for seq in 0..count {
        outlet
            .publish(|scan| {
                scan.header = Header::new(seq, seq * 25_000_000, "laser");
                scan.set_beams(&[1.0, 2.0, 3.0], &[]).unwrap();
            })
            .unwrap();
    }
    outlet.publish_end_of_stream(count, 0).unwrap();
}

/// Receives messages until end of stream; returns their sequence numbers.
fn drain_until_end<T: Message>(inlet: &Inlet<T>) -> Vec<u64> {
    let mut seqs = Vec::new();
    let deadline = Instant::now() + Duration::from_secs(30);
    loop {
        assert!(Instant::now() < deadline, "no end of stream after {seqs:?}");
        wait_any(&[inlet], Duration::from_millis(50)).unwrap();
        while let Some(sample) = inlet.receive().unwrap() {
            let header = Message::header(sample.payload());
            if header.is_end_of_stream() {
                return seqs;
            }
            seqs.push(header.seq);
        }
    }
}

#[test]
fn lossless_stream_delivers_every_message_in_order() {
    let (domain, _cleanup) = scratch_domain("lossless");
    let publisher_domain = domain.clone();
    let sender = std::thread::spawn(move || {
        let node = publisher_domain.node("sender").unwrap();
        let outlet =
            Outlet::create(&publisher_domain, &node, topic::SCAN, Delivery::Lossless, 0).unwrap();
        assert!(
            outlet
                .wait_for_subscribers(1, Some(Duration::from_secs(20)))
                .unwrap()
        );
        publish_scans(&outlet, 500);
    });

    let node = domain.node("receiver").unwrap();
    let inlet = Inlet::open(&node, topic::SCAN).unwrap();
    assert_eq!(inlet.delivery(), Delivery::Lossless);
    let seqs = drain_until_end(&inlet);
    sender.join().unwrap();
    assert_eq!(seqs, (0..500).collect::<Vec<_>>());
}

#[test]
fn a_subscriber_that_waits_before_receiving_loses_nothing() {
    // The topic outlives its first publisher (a subscriber holds it), so it exists without
    // one when the second subscriber opens it: the subscriber must not be made before the
    // next publisher, or that publisher cannot block on it and drops what does not fit its
    // one-message queue while it does not receive.
    let (domain, _cleanup) = scratch_domain("late");
    let (node, first, holder) = scans_to_self(&domain, Delivery::Lossless);
    drop(first);

    let receiver_domain = domain.clone();
    let receiver = std::thread::spawn(move || {
        let node = receiver_domain.node("late-receiver").unwrap();
        let inlet = Inlet::open(&node, topic::SCAN).unwrap();
        // Busy elsewhere (a stage waiting for its own subscribers) before the first receive.
        std::thread::sleep(Duration::from_millis(300));
        drain_until_end(&inlet)
    });
    std::thread::sleep(Duration::from_millis(100));
    let outlet = Outlet::create(&domain, &node, topic::SCAN, Delivery::Lossless, 0).unwrap();
    drop(holder);
    assert!(
        outlet
            .wait_for_subscribers(1, Some(Duration::from_secs(20)))
            .unwrap()
    );
    publish_scans(&outlet, 3);
    assert_eq!(receiver.join().unwrap(), vec![0, 1, 2]);
}

#[test]
fn latest_delivery_drops_the_oldest_and_never_blocks() {
    let (domain, _cleanup) = scratch_domain("latest");
    let (_node, outlet, inlet) = scans_to_self(&domain, Delivery::Latest);
    assert_eq!(inlet.delivery(), Delivery::Latest);
    let total = ipc_types::LATEST_QUEUE as u64 * 3;
    for seq in 0..total {
        outlet
            .publish(|scan| {
                scan.header.seq = seq;
                scan.set_beams(&[1.0, 2.0, 3.0], &[]).unwrap();
            })
            .unwrap();
    }
    let mut seqs = Vec::new();
    while let Some(sample) = inlet.receive().unwrap() {
        seqs.push(sample.header.seq);
    }
    let expected: Vec<u64> = (total - ipc_types::LATEST_QUEUE as u64..total).collect();
    assert_eq!(seqs, expected);
}

#[test]
fn two_domains_never_cross() {
    let a = unique_domain("a");
    let b = unique_domain("b");
    let _cleanup = (Cleanup(a.clone()), Cleanup(b.clone()));
    let node_a = a.node("pub").unwrap();
    let node_b = b.node("pub").unwrap();
    let out_a = Outlet::create(&a, &node_a, topic::SCAN, Delivery::Latest, 0).unwrap();
    let out_b = Outlet::create(&b, &node_b, topic::SCAN, Delivery::Latest, 0).unwrap();
    let in_a = Inlet::open(&a.node("sub").unwrap(), topic::SCAN).unwrap();
    let in_b = Inlet::open(&b.node("sub").unwrap(), topic::SCAN).unwrap();
    out_a.publish(|s| s.header.seq = 1).unwrap();
    out_b.publish(|s| s.header.seq = 2).unwrap();
    out_b.publish(|s| s.header.seq = 3).unwrap();
    assert_eq!(in_a.receive().unwrap().map(|s| s.header.seq), Some(1));
    assert!(in_a.receive().unwrap().is_none());
    assert_eq!(in_b.receive().unwrap().map(|s| s.header.seq), Some(2));
    assert_eq!(in_b.receive().unwrap().map(|s| s.header.seq), Some(3));
}

#[test]
fn history_reaches_a_late_subscriber() {
    let (domain, _cleanup) = scratch_domain("history");
    let node = domain.node("n").unwrap();
    let outlet =
        Outlet::create(&domain, &node, topic::WORLD_CORNERS, Delivery::Lossless, 1).unwrap();
    outlet
        .publish(|w| {
            w.set(&[TrueCorner {
                x: 1.0,
                y: 2.0,
                heading: 0.0,
                angle: 1.57,
            }])
            .unwrap()
        })
        .unwrap();
    let inlet = Inlet::open(&node, topic::WORLD_CORNERS).unwrap();
    outlet.update_connections().unwrap();
    let sample = inlet.receive().unwrap().expect("history sample");
    assert_eq!(sample.corners().len(), 1);
}

#[test]
fn each_end_waits_for_the_other_and_a_timeout_is_kept() {
    let (domain, _cleanup) = scratch_domain("discovery");
    let node = domain.node("main").unwrap();
    // The subscriber comes first and waits for the topic to be created.
    let subscriber_domain = domain.clone();
    let subscriber = std::thread::spawn(move || {
        let node = subscriber_domain.node("subscriber").unwrap();
        let inlet = Inlet::open(&node, topic::POSE).unwrap();
        drain_until_end(&inlet)
    });
    std::thread::sleep(Duration::from_millis(200));
    let outlet = Outlet::create(&domain, &node, topic::POSE, Delivery::Lossless, 0).unwrap();
    assert!(
        outlet
            .wait_for_subscribers(1, Some(Duration::from_secs(20)))
            .unwrap()
    );
    outlet.publish(|pose| pose.header.seq = 7).unwrap();
    outlet.publish_end_of_stream(1, 0).unwrap();
    assert_eq!(subscriber.join().unwrap(), vec![7]);

    // Nobody else subscribes: the wait for a second subscriber ends with its timeout.
    let start = Instant::now();
    let timeout = Duration::from_millis(300);
    assert!(!outlet.wait_for_subscribers(2, Some(timeout)).unwrap());
    assert!(start.elapsed() >= timeout);
}

#[test]
fn bad_domain_names_are_refused() {
    assert!(Domain::new("").is_err());
    assert!(Domain::new("a/b").is_err());
    assert!(Domain::new("under_score").is_err());
    assert!(Domain::new(&"x".repeat(41)).is_err());
    // The user's uid in it: two users' runs of one name never share a file.
    let prefix = Domain::new("run-1").unwrap().file_prefix();
    assert_eq!(prefix, format!("{}run-1_", ipc_types::user_prefix()));
    assert!(prefix.starts_with("slam_u"), "{prefix}");
}

#[test]
fn leftovers_are_removed_once_the_nodes_are_gone() {
    let domain = unique_domain("leftovers");
    {
        let node = domain.node("n").unwrap();
        let _outlet = Outlet::create(&domain, &node, topic::POSE, Delivery::Latest, 0).unwrap();
        assert!(
            !domain
                .leftovers_in(std::path::Path::new("/dev/shm"))
                .unwrap()
                .is_empty()
        );
    }
    domain.remove_leftovers().unwrap();
    assert!(
        domain
            .leftovers_in(std::path::Path::new("/dev/shm"))
            .unwrap()
            .is_empty()
    );
}

#[test]
fn a_claimed_domain_is_refused_to_others_and_swept_at_once_when_its_owner_is_gone() {
    let domain = unique_domain("claim");
    let shm = std::path::Path::new("/dev/shm");
    let claim = domain.claim().unwrap();
    // flock belongs to the open file, so a second claim in this process is refused as
    // another process's would be.
    let refused = domain.claim().unwrap_err();
    assert!(
        matches!(&refused, ClaimError::InUse(name) if name == domain.name()),
        "{refused:?}"
    );
    {
        let node = domain.node("n").unwrap();
        let _outlet = Outlet::create(&domain, &node, topic::POSE, Delivery::Latest, 0).unwrap();
    }
    // A live owner's domain is its own, however young or idle.
    Domain::sweep_abandoned();
    assert!(!domain.leftovers_in(shm).unwrap().is_empty());

    // The owner dies (the lock goes with its file descriptor): its files go at the next
    // sweep, without waiting for them to age.
    drop(claim);
    let cleaned = Domain::sweep_abandoned().cleaned;
    assert!(
        cleaned.iter().any(|name| name == domain.name()),
        "{cleaned:?}"
    );
    assert!(domain.leftovers_in(shm).unwrap().is_empty());
    // And the domain can be claimed again.
    drop(domain.claim().unwrap());
    domain.remove_leftovers().unwrap();
}

#[test]
fn a_planted_fifo_or_link_as_owner_file_is_reported_not_opened() {
    let shm = std::path::Path::new("/dev/shm");
    for planted in ["fifo", "link"] {
        let domain = unique_domain(planted);
        let owner = shm.join(format!("{}owner.lock", domain.file_prefix()));
        match planted {
            "fifo" => nix::unistd::mkfifo(&owner, nix::sys::stat::Mode::from_bits_truncate(0o666))
                .unwrap(),
            _ => std::os::unix::fs::symlink("/dev/zero", &owner).unwrap(),
        }
        // A blocking open of the FIFO would never return: the sweep must come back.
        let sweep = Domain::sweep_abandoned();
        let reported: Vec<_> = sweep.foreign.iter().map(|f| f.path.clone()).collect();
        assert!(reported.contains(&owner), "{planted}: {reported:?}");
        assert!(!sweep.cleaned.iter().any(|name| name == domain.name()));
        assert!(owner.symlink_metadata().is_ok(), "{planted} left in place");
        let refused = domain.claim().unwrap_err();
        assert!(
            matches!(&refused, ClaimError::Foreign { file, .. } if file.path == owner),
            "{planted}: {refused:?}"
        );
        std::fs::remove_file(&owner).unwrap();
    }
}

#[test]
fn a_lossy_reader_is_never_waited_for_and_loses_what_does_not_fit() {
    let (domain, _cleanup) = scratch_domain("lossy");
    let node = domain.node("both").unwrap();
    let outlet = Outlet::create(&domain, &node, topic::SCAN, Delivery::Lossless, 0).unwrap();
    let view = Inlet::open_lossy(&node, topic::SCAN).unwrap();
    assert_eq!(view.delivery(), Delivery::Lossless);
    // Not one of the pipeline's readers: a publisher waiting for one does not start for it.
    assert_eq!(outlet.subscriber_count(), 0);
    assert!(
        !outlet
            .wait_for_subscribers(1, Some(Duration::from_millis(200)))
            .unwrap()
    );

    let reader_domain = domain.clone();
    let reader = std::thread::spawn(move || {
        let node = reader_domain.node("reader").unwrap();
        let inlet = Inlet::open(&node, topic::SCAN).unwrap();
        drain_until_end(&inlet)
    });
    assert!(
        outlet
            .wait_for_subscribers(1, Some(Duration::from_secs(20)))
            .unwrap()
    );
    assert_eq!(outlet.subscriber_count(), 1);
    // The lossy reader takes nothing while they are sent: the sends do not wait for it.
    publish_scans(&outlet, 200);
    assert_eq!(reader.join().unwrap(), (0..200).collect::<Vec<_>>());
    let mut seen = Vec::new();
    while let Some(sample) = view.receive().unwrap() {
        seen.push(sample.header.seq);
    }
    // Its queue kept the first messages, about 2 MiB of them; every later one was not
    // delivered to it.
    let kept = seen.len();
    assert_eq!(seen, (0..kept as u64).collect::<Vec<_>>());
    let bytes = kept * std::mem::size_of::<ipc_types::prelude::LaserScan>();
    assert!(kept > 1 && (1 << 20..=2 << 20).contains(&bytes), "{kept}");
}
