//! What the live path adds between a frame's weights and its UDP send: one VMC bundle (every
//! blendshape moved, the head turned) encoded and sent to a loopback socket, for the built-in
//! head's 52 shapes and for a 124-shape VRoid-sized face.
#![allow(missing_docs, clippy::unwrap_used, reason = "a benchmark")]

use criterion::{Criterion, criterion_group, criterion_main};
use faceanim_live::{Names, Performer};

fn send(c: &mut Criterion) {
    let receiver = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
    let character = faceanim_head::default_character();
    let own: Vec<String> = character.blendshape_names();
    let many: Vec<String> = (0..124).map(|i| format!("Fcl_shape_{i:03}")).collect();
    for (label, names, mode) in [
        ("52 ARKit shapes", &own, Names::Arkit),
        ("124 own shapes", &many, Names::Own),
    ] {
        let mut performer = Performer::new(receiver.local_addr().unwrap(), names, mode).unwrap();
        let mut k = 0u32;
        c.bench_function(&format!("VMC frame to UDP send ({label})"), |b| {
            b.iter(|| {
                k += 1;
                // Every value moves, so every value is sent.
                let value = (k % 100) as f32 / 100.0;
                let weights = vec![value; names.len()];
                performer.send(&weights, Some([value * 20.0, 0.0, 0.0]), k as f32 / 60.0)
            });
        });
        // Empty the receiver's buffer between groups so sends keep succeeding.
        receiver.set_nonblocking(true).unwrap();
        let mut buffer = [0u8; 65536];
        while receiver.recv_from(&mut buffer).is_ok() {}
    }
}

criterion_group!(benches, send);
criterion_main!(benches);
