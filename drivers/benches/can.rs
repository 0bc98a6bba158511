//! CAN benchmarks: frames per second through the slcan codec, and the CANopen master's
//! CPU time per SYNC cycle with 3 and 6 CiA 402 drives (minimal drives on the in-memory
//! bus, so the figure is the master's own work plus the bus hand-over).

use std::collections::HashMap;

use divan::counter::ItemsCount;
use klar_drivers::can::CanFrame;
use klar_drivers::can::memory::{BusDevice, MemoryBus};
use klar_drivers::can::slcan::{SlcanDecoder, encode_frame};
use klar_drivers::cia402::state::{PowerState, transition};
use klar_drivers::cia402::{CanOpenConfig, Cia402Backend};
use klar_motion::{AxisBackend, AxisFeedback, Setpoint};

fn main() {
    divan::main();
}

const FRAMES: usize = 1000;

fn sample_frames() -> Vec<CanFrame> {
    (0..FRAMES)
        .map(|i| {
            let b = (i as u32).to_le_bytes();
            CanFrame::standard(
                0x180 + (i % 127) as u16 + 1,
                &[0x37, 0x06, b[0], b[1], b[2], b[3], 0x08, 0x00],
            )
            .unwrap_or_else(|_| CanFrame::fixed(0x181, &[]))
        })
        .collect()
}

/// Encodes 1000 eight-byte frames.
#[divan::bench]
fn slcan_encode(bencher: divan::Bencher) {
    let frames = sample_frames();
    let mut out = Vec::with_capacity(FRAMES * 32);
    bencher.counter(ItemsCount::new(FRAMES)).bench_local(|| {
        out.clear();
        for f in &frames {
            encode_frame(f, &mut out);
        }
        divan::black_box(out.len())
    });
}

/// Decodes 1000 eight-byte frames from one byte stream.
#[divan::bench]
fn slcan_decode(bencher: divan::Bencher) {
    let mut bytes = Vec::new();
    for f in &sample_frames() {
        encode_frame(f, &mut bytes);
    }
    let mut msgs = Vec::with_capacity(FRAMES);
    bencher.counter(ItemsCount::new(FRAMES)).bench_local(|| {
        msgs.clear();
        SlcanDecoder::new().feed(&bytes, &mut msgs);
        divan::black_box(msgs.len())
    });
}

/// The least a CiA 402 drive must do for the master: boot, keep SDO-written values
/// (expedited only), follow the controlword and echo the target as position on SYNC.
struct MinimalDrive {
    node: u16,
    values: HashMap<(u16, u8), [u8; 4]>,
    state: PowerState,
    controlword: u16,
    target: [u8; 4],
}

impl BusDevice for MinimalDrive {
    fn start(&mut self, out: &mut Vec<CanFrame>) {
        out.push(CanFrame::fixed(0x700 + self.node, &[0]));
    }

    fn on_frame(&mut self, f: &CanFrame, out: &mut Vec<CanFrame>) {
        let Some(id) = f.id().standard() else { return };
        let d = f.data();
        if id == 0
            && d.get(1)
                .is_some_and(|&n| n == 0 || u16::from(n) == self.node)
            && d.first() == Some(&0x82)
        {
            out.push(CanFrame::fixed(0x700 + self.node, &[0]));
        } else if id == 0x600 + self.node && d.len() == 8 {
            let key = (u16::from_le_bytes([d[1], d[2]]), d[3]);
            let answer = if d[0] >> 5 == 1 {
                let mut v = [0u8; 4];
                v.copy_from_slice(&d[4..8]);
                if key.0 == 0x6060 {
                    self.values.insert((0x6061, 0), v);
                }
                self.values.insert(key, v);
                [0x60, d[1], d[2], d[3], 0, 0, 0, 0]
            } else {
                let v = self.values.get(&key).copied().unwrap_or([0; 4]);
                [0x43, d[1], d[2], d[3], v[0], v[1], v[2], v[3]]
            };
            out.push(CanFrame::fixed(0x580 + self.node, &answer));
        } else if id == 0x200 + self.node && d.len() == 6 {
            self.controlword = u16::from_le_bytes([d[0], d[1]]);
            self.target.copy_from_slice(&d[2..6]);
        } else if id == 0x080 {
            self.state = transition(self.state, self.controlword, false);
            let sw = self.state.statusword_bits().to_le_bytes();
            let t = self.target;
            out.push(CanFrame::fixed(
                0x180 + self.node,
                &[sw[0], sw[1], t[0], t[1], t[2], t[3]],
            ));
        }
    }
}

fn backend(drives: u8, period: f64) -> Cia402Backend {
    let mut text =
        String::from("bus = { adapter = \"sim\", bitrate = 1000000 }\nheartbeat_ms = 0\n");
    for n in 1..=drives {
        text.push_str(&format!(
            "[[drives]]\nnode = {n}\ncounts_per_unit = 1000.0\n"
        ));
    }
    let config: CanOpenConfig =
        toml::from_str(&text).unwrap_or_else(|e| panic!("bench config: {e}"));
    let bus = MemoryBus::new();
    let endpoint = bus.endpoint();
    for n in 1..=drives {
        bus.attach(Box::new(MinimalDrive {
            node: u16::from(n),
            values: HashMap::new(),
            state: PowerState::SwitchOnDisabled,
            controlword: 0,
            target: [0; 4],
        }));
    }
    let mut b = Cia402Backend::with_bus(&config, period, Box::new(endpoint))
        .unwrap_or_else(|e| panic!("bench start: {e}"));
    b.enable().unwrap_or_else(|e| panic!("bench enable: {e}"));
    b
}

/// One servo cycle (RPDOs, SYNC, TPDOs, state evaluation) with `N` drives.
#[divan::bench(consts = [3, 6])]
fn master_cycle<const N: u8>(bencher: divan::Bencher) {
    // Six drives need 2 ms at 1 Mbit/s (bus-load check); the CPU time does not depend on it.
    let period = if N > 3 { 0.002 } else { 0.001 };
    let mut b = backend(N, period);
    let mut fb = vec![AxisFeedback::default(); usize::from(N)];
    let mut t = 0.0;
    let mut k = 0u32;
    bencher.bench_local(|| {
        t += period;
        k += 1;
        let p = f64::from(k % 1000) * 0.001;
        let sps = vec![
            Setpoint {
                position: p,
                ..Default::default()
            };
            usize::from(N)
        ];
        b.cycle(t, &sps, &mut fb)
            .unwrap_or_else(|e| panic!("cycle: {e}"));
        divan::black_box(fb[0].position)
    });
}
