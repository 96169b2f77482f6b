//! An in-memory sensor for unit tests: scripted replies in, written commands out.

use std::io::{self, Read, Write};

use crate::scip::{
    Information, Ranging, Reply, SensorParams, Status, data_line, encode, information_line,
    scan_body,
};

/// Replays `input`, records what is written. At the end of the input it reports a closed
/// connection, or, when silent, read timeouts for ever.
#[derive(Debug, Default)]
pub struct ScriptedStream {
    input: Vec<u8>,
    at: usize,
    written: Vec<u8>,
    silent_at_end: bool,
}

impl ScriptedStream {
    pub fn new(input: Vec<u8>) -> Self {
        Self {
            input,
            ..Self::default()
        }
    }

    /// A sensor that never says anything.
    pub fn silent() -> Self {
        Self {
            silent_at_end: true,
            ..Self::default()
        }
    }

    pub fn written(&self) -> &[u8] {
        &self.written
    }
}

impl Read for ScriptedStream {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        if self.at >= self.input.len() {
            if self.silent_at_end {
                std::thread::sleep(std::time::Duration::from_millis(1));
                return Err(io::ErrorKind::WouldBlock.into());
            }
            return Ok(0);
        }
        let n = buf.len().min(self.input.len() - self.at);
        buf[..n].copy_from_slice(&self.input[self.at..self.at + n]);
        self.at += n;
        Ok(n)
    }
}

impl Write for ScriptedStream {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        self.written.extend_from_slice(buf);
        Ok(buf.len())
    }

    fn flush(&mut self) -> io::Result<()> {
        Ok(())
    }
}

/// A reply's bytes; `status` is two characters.
pub fn reply(echo: &[u8], status: &[u8], body: &[Vec<u8>]) -> Vec<u8> {
    Reply {
        echo: echo.to_vec(),
        status: Status([status[0], status[1]]),
        body: body.to_vec(),
    }
    .to_bytes()
}

fn information(info: &Information) -> Vec<Vec<u8>> {
    info.0
        .iter()
        .map(|(name, value)| information_line(name, value))
        .collect()
}

/// One scan of `ranging` as the sensor sends it.
pub fn scan_reply(
    ranging: &Ranging,
    timestamp_ms: u32,
    ranges: &[u32],
    intensities: &[u32],
) -> Vec<u8> {
    let body = scan_body(ranging.kind, timestamp_ms, ranges, intensities).unwrap();
    reply(&ranging.echo(0), b"99", &body)
}

/// The replies of a UTM-30LX to QT, VV, PP, II and, when `counters` is not empty, TM0,
/// one TM1 per counter value, TM2.
pub fn utm_handshake(counters: &[u32]) -> Vec<u8> {
    let mut script = reply(b"QT", b"00", &[]);
    let version = Information(vec![
        ("VEND".into(), "Hokuyo Automatic Co.,Ltd.".into()),
        ("PROD".into(), "SOKUIKI Sensor UTM-30LX".into()),
        ("FIRM".into(), "1.0.0".into()),
        ("PROT".into(), "SCIP 2.0".into()),
        ("SERI".into(), "H0000000".into()),
    ]);
    script.extend(reply(b"VV", b"00", &information(&version)));
    script.extend(reply(
        b"PP",
        b"00",
        &information(&SensorParams::utm_30lx().to_information()),
    ));
    let status = Information(vec![("LASR".into(), "OFF".into())]);
    script.extend(reply(b"II", b"00", &information(&status)));
    if !counters.is_empty() {
        script.extend(reply(b"TM0", b"00", &[]));
        for &counter in counters {
            let stamp = data_line(&encode(counter, 4).unwrap());
            script.extend(reply(b"TM1", b"00", &[stamp]));
        }
        script.extend(reply(b"TM2", b"00", &[]));
    }
    script
}
