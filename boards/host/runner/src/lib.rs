//! # imu-emu-runner — the host runner
//!
//! Runs emulated IMUs — an Inertial Labs KERNEL or an Inertial Sense
//! IMX-5 speaking ISB ([`imu_emu::device::Device`] with either
//! personality), one or a fleet — in real time, scaled or as fast as
//! possible, and exposes each one's UART on a TCP port, a pseudo-terminal
//! or a serial port:
//!
//! * [`runner`] — the loop: the core's shared tick/pump schedule
//!   ([`imu_emu::schedule`]: ticks on absolute deadlines, line-rate pacing
//!   with [`imu_emu::Pacer`], input) with bounded work per pass, and
//!   sleeping;
//! * [`clock`] — device time against the host clock (`--speed`);
//! * [`transport`] — TCP ([`transport::TcpTransport`]), pty
//!   ([`transport::PtyTransport`]) and serial with a bounded [`backlog`];
//! * [`flash`] — the device's NOR flash, optionally written through to a
//!   file so a restart is a power cycle;
//! * [`control`] — the control socket: 1PPS/EXTRIG edges, power cycle
//!   with BOOT, `status`, link faults, TOV edges reported back as events;
//! * [`link`] — link-level faults between the device and the transport
//!   (drop, corrupt, duplicate, noise, stall, cut), seeded by `--seed`;
//! * [`monitor`] — the KERNEL's input decoded on the host side: logs and
//!   the reasons frames are rejected;
//! * [`trajectory`], [`vehicle`] — motion replayed from CSV, scripted
//!   motion;
//! * [`feed`] — `--motion-feed ADDR`: live motion samples (real time or
//!   lockstep);
//! * [`fleet`] — `--count N`: many devices in one loop;
//! * [`web`] — `--web ADDR`: the live web view (its own thread, fed by
//!   the runners without blocking them);
//! * [`virtual_device`] — an in-process virtual KERNEL for Rust driver
//!   tests (`std::io` and `embedded_io` `Read + Write`, simulated time);
//! * [`mod@unit`] — a unit run in process for `imu-emu allan` (no line, as
//!   fast as the host computes);
//! * [`uart`] — what a UART at the wrong rate reads (pty baud mismatch);
//! * [`error`] — the bind errors, below every other module.
//!
//! It builds on the core and on the tools crate (`imu_emu_tools`: the
//! protocol choice, the usage error, the decoders of the web view, the
//! unit `imu-emu allan` asks for); the
//! `imu-emu` program's command line wires it up.
#![forbid(unsafe_code)]
#![deny(missing_docs)]

pub mod backlog;
pub mod clock;
pub mod control;
pub mod error;
pub mod feed;
pub mod flash;
pub mod fleet;
pub mod link;
pub mod monitor;
pub mod protocol;
pub mod runner;
pub mod trajectory;
pub mod transport;
pub mod uart;
pub mod unit;
pub mod vehicle;
pub mod virtual_device;
pub mod web;
