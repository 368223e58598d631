//! # imu-emu-host — the host runner board
//!
//! Runs one virtual KERNEL IMU ([`imu_emu::device::Device`]) in real time
//! and exposes its UART on a TCP port or a pseudo-terminal:
//!
//! * [`runner`] — the loop: the core's shared tick/pump schedule
//!   ([`imu_emu::schedule`]: ticks on absolute deadlines, line-rate pacing
//!   with [`imu_emu::Pacer`], input) with bounded work per pass, and
//!   sleeping;
//! * [`clock`] — device time against the host clock (`--speed`);
//! * [`transport`] — TCP ([`transport::TcpTransport`]) and pty
//!   ([`transport::PtyTransport`]) with a bounded [`backlog`];
//! * [`flash`] — the device's NOR flash, optionally written through to a
//!   file so a restart is a power cycle;
//! * [`control`] — the control socket: 1PPS/EXTRIG edges, power cycle
//!   with BOOT, `status`, link faults, TOV edges reported back as events;
//! * [`link`] — link-level faults between the device and the transport
//!   (drop, corrupt, duplicate, noise, stall, cut), seeded by `--seed`;
//! * [`monitor`] — the device's input decoded on the host side: logs and
//!   the reasons frames are rejected;
//! * [`trajectory`] — `--trajectory FILE`: motion replayed from CSV;
//! * [`feed`] — `--motion-feed ADDR`: live motion samples (real time or
//!   lockstep);
//! * [`virtual_device`] — an in-process virtual KERNEL for Rust driver
//!   tests (`std::io` and `embedded_io` `Read + Write`, simulated time);
//! * [`uart`] — what a UART at the wrong rate reads (pty baud mismatch);
//! * [`error`] — [`error::UsageError`] (exit status 2) and the bind
//!   errors, below every other module;
//! * [`cli`] — the command line and [`cli::run`], what `main` calls;
//! * [`client`] — `imu-emu client …`: the host side of a KERNEL line
//!   (commands, record, decode, plot);
//! * [`web`] — `--web ADDR`: the live web view (its own thread, fed by
//!   the runners without blocking them);
//! * [`plot`] — the one plot style (titled panels, labelled axes with
//!   units, legend; PNG or SVG; embedded font).
#![forbid(unsafe_code)]
#![deny(missing_docs)]

pub mod allan;
pub mod allan_input;
pub mod allan_plot;
pub mod backlog;
pub mod cli;
pub mod client;
pub mod clock;
pub mod control;
pub mod error;
pub mod feed;
pub mod flash;
pub mod fleet;
pub mod link;
pub mod monitor;
pub mod plot;
pub mod profile_file;
pub mod runner;
pub mod trajectory;
pub mod transport;
pub mod uart;
pub mod vehicle;
pub mod virtual_device;
pub mod web;
