//! A transport in memory for the runner's unit tests: input queued by the
//! test, output kept, always connected, never waited on.

use std::collections::VecDeque;
use std::time::Duration;

use crate::transport::Transport;

/// What the runner sees of a client that reads everything at once.
#[derive(Debug, Default)]
pub(super) struct Mem {
    /// Input the client sent, not read yet.
    pub input: VecDeque<u8>,
    /// Everything the runner sent.
    pub sent: Vec<u8>,
    /// The runner holds input back ([`Transport::hold_input`]).
    pub held: bool,
    /// The last line rate set, bit/s.
    pub rate: Option<u32>,
}

impl Mem {
    /// A client that has sent `input`.
    pub fn with_input(input: &[u8]) -> Self {
        Mem {
            input: input.iter().copied().collect(),
            ..Mem::default()
        }
    }
}

impl Transport for Mem {
    fn describe(&self) -> String {
        "mem test".to_owned()
    }

    fn wait(&mut self, _timeout: Duration) -> anyhow::Result<()> {
        Ok(())
    }

    fn interest<'a>(&'a self, _fds: &mut Vec<nix::poll::PollFd<'a>>) {}

    fn polled(&mut self, _revents: &[nix::poll::PollFlags]) {}

    fn receive(&mut self, max: usize, sink: &mut dyn FnMut(&[u8])) -> anyhow::Result<()> {
        let n = max.min(self.input.len());
        let bytes: Vec<u8> = self.input.drain(..n).collect();
        if !bytes.is_empty() {
            sink(&bytes);
        }
        Ok(())
    }

    fn send(&mut self, bytes: &[u8]) -> anyhow::Result<()> {
        self.sent.extend_from_slice(bytes);
        Ok(())
    }

    fn hold_input(&mut self, hold: bool) {
        self.held = hold;
    }

    fn flush(&mut self) -> anyhow::Result<()> {
        Ok(())
    }

    fn set_line_rate(&mut self, bps: u32) -> anyhow::Result<()> {
        self.rate = Some(bps);
        Ok(())
    }

    fn backlog_len(&self) -> usize {
        0
    }

    fn backlog_dropped(&self) -> u64 {
        0
    }

    fn connected(&self) -> bool {
        true
    }

    fn poll_client(&mut self) -> anyhow::Result<bool> {
        Ok(true)
    }
}
