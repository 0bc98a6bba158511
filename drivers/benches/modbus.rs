//! Modbus RTU transactions per second over a pseudo-terminal (115200 baud configured;
//! a pty moves bytes without baud-rate pacing, so this measures the software path:
//! framing, CRC, tokio-modbus and klar's link). The wire-time bound at 115200 baud is
//! printed next to it from the framing rules.

use std::future::{Ready, ready};

use divan::Bencher;
use klar_drivers::modbus::limits::{read_time, write_multiple_time};
use klar_drivers::modbus::{ModbusLink, Parity, RegisterTable, SerialLineConfig};
use tokio_modbus::prelude::{ExceptionCode, Request, Response, SlaveRequest};
use tokio_modbus::server::Service;
use tokio_serial::SerialPortBuilderExt;

struct Echo;

impl Service for Echo {
    type Request = SlaveRequest<'static>;
    type Response = Option<Response>;
    type Exception = ExceptionCode;
    type Future = Ready<Result<Option<Response>, ExceptionCode>>;

    fn call(&self, req: Self::Request) -> Self::Future {
        ready(Ok(Some(match req.request {
            Request::ReadHoldingRegisters(a, n) => {
                Response::ReadHoldingRegisters((a..a.saturating_add(n)).collect())
            }
            Request::WriteMultipleRegisters(a, v) => {
                Response::WriteMultipleRegisters(a, v.len() as u16)
            }
            _ => return ready(Err(ExceptionCode::IllegalFunction)),
        })))
    }
}

struct Rig {
    runtime: tokio::runtime::Runtime,
    link: ModbusLink,
}

fn rig() -> Rig {
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .expect("runtime");
    let link = runtime.block_on(async {
        let (master, slave) = tokio_serial::SerialStream::pair().expect("pty pair");
        let path = tokio_serial::SerialPort::name(&slave).expect("pty name");
        tokio::spawn(async move {
            let _ = tokio_modbus::server::rtu::Server::new(master)
                .serve_forever(Echo)
                .await;
        });
        let client = tokio_serial::new(&path, 115_200)
            .open_native_async()
            .expect("open pty");
        drop(slave);
        ModbusLink::from_stream(client, 1, std::time::Duration::from_millis(200), 0)
    });
    Rig { runtime, link }
}

#[divan::bench]
fn read_4_holding_registers(bencher: Bencher) {
    let mut r = rig();
    bencher.bench_local(|| {
        r.runtime
            .block_on(r.link.read(RegisterTable::Holding, 0x2100, 4))
            .expect("read")
    });
}

#[divan::bench]
fn write_2_registers(bencher: Bencher) {
    let mut r = rig();
    bencher.bench_local(|| {
        r.runtime
            .block_on(r.link.write_multiple(0x0100, &[0x0001, 0x86A0]))
            .expect("write")
    });
}

fn main() {
    let mut line = SerialLineConfig::new("wire");
    line.baud = 115_200;
    line.parity = Parity::None;
    line.turnaround = 0.0;
    let read = read_time(&line, 4);
    let write = write_multiple_time(&line, 2);
    println!(
        "wire-time bound at 115200 8N1 (no device turnaround): read 4 regs {:.2} ms \
         ({:.0}/s), write 2 regs {:.2} ms ({:.0}/s)",
        read * 1e3,
        1.0 / read,
        write * 1e3,
        1.0 / write
    );
    divan::main();
}
