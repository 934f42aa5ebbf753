//! Round-trip latency of the physics–haptics exchange (one probe out, one
//! sample back) against an echo responder thread, over loopback UDP and the
//! in-process link. Prints one JSON object (times in µs).
//!
//! `cargo bench -p echothigh-transport --bench link [-- N]` (N round trips,
//! default 5000).

use echothigh_transport::{
    connect, in_process_pair, measure_round_trips, EchoResponder, FaultConfig, Link, ListenConfig,
    RoundTripReport, SessionToken, UdpServer,
};
use std::time::Duration;

fn json(name: &str, r: &RoundTripReport) -> String {
    format!(
        "\"{name}\": {{\"count\": {}, \"min_us\": {:.2}, \"median_us\": {:.2}, \"p99_us\": {:.2}, \"max_us\": {:.2}}}",
        r.count,
        r.min * 1e6,
        r.median * 1e6,
        r.p99 * 1e6,
        r.max * 1e6
    )
}

fn main() {
    let count = std::env::args()
        .skip(1)
        .find_map(|a| a.parse::<usize>().ok())
        .unwrap_or(5000);
    let timeout = Duration::from_secs(2);
    let none = FaultConfig::default();

    let server = UdpServer::bind(&ListenConfig {
        addr: "127.0.0.1:0".parse().expect("literal address"),
        allow_remote: false,
    })
    .expect("bind loopback");
    let addr = server.local_addr().expect("local address");
    let token = SessionToken::generate();
    let accept = std::thread::spawn(move || server.accept(&token, none, 100.0, timeout, 0.0));
    let (mut client, _) = connect(addr, &token, none, timeout, 0.0).expect("handshake");
    let responder = EchoResponder::spawn(accept.join().expect("accept thread").expect("accept"));
    let udp = measure_round_trips(&mut client, 200, count, timeout)
        .expect("udp round trips")
        .expect("samples");
    client.close(0.0).expect("close");
    responder.stop().expect("udp responder");

    let (mut a, b) = in_process_pair(1, none, none);
    let responder = EchoResponder::spawn(b);
    let mem = measure_round_trips(&mut a, 200, count, timeout)
        .expect("in-process round trips")
        .expect("samples");
    a.close(0.0).expect("close");
    responder.stop().expect("in-process responder");

    println!(
        "{{{}, {}}}",
        json("udp_loopback", &udp),
        json("in_process", &mem)
    );
}
