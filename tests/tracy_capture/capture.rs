//! A minimal Tracy server: connects to a running client, takes everything it sends until it
//! terminates, asks for the names behind its pointers (source locations, strings, threads,
//! plots) as the profiler does, and keeps what the test checks: zones by name, per-thread
//! nesting, thread names, frame marks, plot values, GPU contexts and GPU zones with their
//! timestamps. It reads what a profiler would receive; drawing it is Tracy's.

use super::protocol::{self, Trailer, event, query};
use std::collections::{BTreeMap, BTreeSet, HashMap, HashSet, VecDeque};
use std::io::{Read, Write};
use std::net::TcpStream;
use std::time::Duration;

/// One GPU zone: its name, context, and GPU timestamps (ticks) once they arrived, with those
/// times put on the CPU's timeline (nanoseconds) by the context's latest tie of the two clocks,
/// as the profiler draws them.
#[derive(Clone, Debug)]
pub struct GpuZone {
    pub name: String,
    #[allow(dead_code)] // kept for the failure messages (Debug)
    pub context: u8,
    pub begin: Option<i64>,
    pub end: Option<i64>,
    pub cpu_begin_ns: Option<f64>,
    pub cpu_end_ns: Option<f64>,
}

/// One CPU zone: its name, thread, and times (nanoseconds on the client's clock).
#[derive(Clone, Debug)]
pub struct CpuZone {
    pub name: String,
    pub thread: String,
    pub begin_ns: f64,
    pub end_ns: Option<f64>,
}

/// A GPU context: its name and nanoseconds per tick.
#[derive(Clone, Debug, Default)]
pub struct GpuContext {
    pub name: Option<String>,
    pub period_ns: f32,
    /// The latest tie of its clock to the CPU's: (GPU ticks, CPU time in the client's units).
    pub tie: (i64, i64),
    /// `GpuCalibration` and `GpuTimeSync` events: the ties of its clock to the CPU's.
    pub clock_ties: usize,
}

/// What a capture received.
#[derive(Debug, Default)]
pub struct Capture {
    pub program: String,
    /// Nanoseconds per unit of the client's CPU clock.
    pub timer_ns: f64,
    /// Every CPU zone, in the order they began.
    pub cpu_zones: Vec<CpuZone>,
    /// CPU zones begun, by name, with the names of the threads they ran on.
    pub zones: BTreeMap<String, usize>,
    pub zone_threads: BTreeMap<String, BTreeSet<String>>,
    /// Zone ends without a begin on their thread, and zones left open at the end.
    pub nesting_errors: Vec<String>,
    pub thread_names: BTreeMap<u32, String>,
    pub frame_marks: usize,
    pub plots: BTreeMap<String, Vec<f64>>,
    pub gpu_contexts: BTreeMap<u8, GpuContext>,
    pub gpu_zones: Vec<GpuZone>,
    /// GPU timestamps for a query no zone was waiting on.
    pub stray_gpu_times: usize,
}

/// Where a zone's name comes from: a static source location (a pointer to ask about) or one
/// the client allocated and sent ahead of the zone.
#[derive(Clone, Debug)]
enum ZoneName {
    Static(u64),
    Sent(String),
}

/// A CPU zone as it arrives: its name source, thread, and begin and end times (client units).
struct ZoneRecord {
    name: ZoneName,
    thread: u32,
    begin: i64,
    end: Option<i64>,
}

/// A source location the client described: pointers to its name and function.
#[derive(Clone, Copy, Debug)]
struct SourceLocation {
    name: u64,
    function: u64,
}

#[derive(Default)]
struct State {
    capture: Capture,
    thread: u32,
    /// Open CPU zones per thread.
    open: HashMap<u32, Vec<usize>>,
    /// Every CPU zone begun: its name source, thread, and begin and end times.
    zones: Vec<ZoneRecord>,
    /// The thread's time reference: its events carry the difference to the previous one.
    thread_time: i64,
    gpu_names: Vec<ZoneName>,
    /// Open GPU zones per context.
    open_gpu: HashMap<u8, Vec<usize>>,
    strings: HashMap<u64, String>,
    source_locations: HashMap<u64, SourceLocation>,
    plot_names: HashMap<u64, String>,
    plot_values: Vec<(u64, f64)>,
    /// The last allocated source location or single string, for the event that follows it.
    payload: Option<String>,
    single_string: Option<String>,
    /// GPU time reference: each `GpuTime` carries the difference to the previous one.
    gpu_time: i64,
    /// (context, query id) → (GPU zone, whether it is the zone's end).
    gpu_queries: HashMap<(u8, u16), (usize, bool)>,
    /// Queries to send, and those sent whose answers have not arrived.
    to_ask: VecDeque<(u8, u64)>,
    asked: HashSet<(u8, u64)>,
    source_location_answers: VecDeque<u64>,
    outstanding: usize,
    terminated: bool,
    /// Threads seen, whose names are asked for at the end.
    threads_to_name: Vec<u32>,
}

/// Connects to the client on `port` (retrying while it starts), then reads until it has sent
/// everything and answered every question.
pub fn capture(port: u16, patience: Duration) -> Result<Capture, String> {
    let start = std::time::Instant::now();
    let mut stream = loop {
        match TcpStream::connect(("127.0.0.1", port)) {
            Ok(s) => break s,
            Err(_) if start.elapsed() < patience => {
                std::thread::sleep(Duration::from_millis(20));
            }
            Err(e) => return Err(format!("no Tracy client on port {port}: {e}")),
        }
    };
    stream
        .set_read_timeout(Some(patience))
        .map_err(|e| e.to_string())?;
    stream
        .write_all(protocol::SHIBBOLETH)
        .map_err(|e| e.to_string())?;
    stream
        .write_all(&protocol::PROTOCOL_VERSION.to_le_bytes())
        .map_err(|e| e.to_string())?;
    let mut status = [0u8; 1];
    stream
        .read_exact(&mut status)
        .map_err(|e| format!("handshake: {e}"))?;
    if status[0] != protocol::HANDSHAKE_WELCOME {
        return Err(format!(
            "handshake refused with status {} (2: protocol mismatch)",
            status[0]
        ));
    }
    let mut welcome = vec![0u8; protocol::WELCOME_SIZE];
    stream
        .read_exact(&mut welcome)
        .map_err(|e| format!("welcome message: {e}"))?;
    let name = &welcome[protocol::WELCOME_PROGRAM_NAME..protocol::WELCOME_PROGRAM_NAME + 64];
    let mut state = State::default();
    state.capture.program = c_string(name);
    state.capture.timer_ns = f64::from_le_bytes(welcome[..8].try_into().unwrap());

    let mut window: Vec<u8> = Vec::new();
    let mut pending: Vec<u8> = Vec::new();
    let mut frame = vec![0u8; protocol::TARGET_FRAME_SIZE];
    loop {
        state.send_queries(&mut stream)?;
        if state.terminated && state.outstanding == 0 && state.to_ask.is_empty() {
            stream
                .write_all(&query_packet(query::TERMINATE, 0))
                .map_err(|e| e.to_string())?;
            break;
        }
        let mut size = [0u8; 4];
        stream
            .read_exact(&mut size)
            .map_err(|e| format!("reading a frame's size: {e}"))?;
        let size = u32::from_le_bytes(size) as usize;
        let mut compressed = vec![0u8; size];
        stream
            .read_exact(&mut compressed)
            .map_err(|e| format!("reading a frame: {e}"))?;
        let n = lz4_flex::block::decompress_into_with_dict(&compressed, &mut frame, &window)
            .map_err(|e| format!("LZ4: {e}"))?;
        window.extend_from_slice(&frame[..n]);
        if window.len() > protocol::LZ4_WINDOW {
            window.drain(..window.len() - protocol::LZ4_WINDOW);
        }
        pending.extend_from_slice(&frame[..n]);
        let used = state.read_events(&pending)?;
        pending.drain(..used);
    }
    // The client closes once it has read the terminate query; what it still sends is not needed.
    let mut rest = Vec::new();
    let _ = stream.read_to_end(&mut rest);
    Ok(state.finish())
}

/// A zone begin's or end's time difference as sent in the full 64-bit event: a difference too
/// large for the 32-bit event is sent less [`protocol::TIME_OFFSET_64`] (a negative one as is).
fn full_delta(sent: i64) -> i64 {
    if sent >= 0 {
        sent + protocol::TIME_OFFSET_64
    } else {
        sent
    }
}

fn query_packet(kind: u8, ptr: u64) -> [u8; 13] {
    let mut packet = [0u8; 13];
    packet[0] = kind;
    packet[1..9].copy_from_slice(&ptr.to_le_bytes());
    packet
}

fn c_string(bytes: &[u8]) -> String {
    let end = bytes.iter().position(|&b| b == 0).unwrap_or(bytes.len());
    String::from_utf8_lossy(&bytes[..end]).into_owned()
}

fn u16_at(b: &[u8], at: usize) -> u16 {
    u16::from_le_bytes(b[at..at + 2].try_into().unwrap())
}
fn u32_at(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes(b[at..at + 4].try_into().unwrap())
}
fn u64_at(b: &[u8], at: usize) -> u64 {
    u64::from_le_bytes(b[at..at + 8].try_into().unwrap())
}
fn i64_at(b: &[u8], at: usize) -> i64 {
    u64_at(b, at) as i64
}
fn f32_at(b: &[u8], at: usize) -> f32 {
    f32::from_le_bytes(b[at..at + 4].try_into().unwrap())
}
fn f64_at(b: &[u8], at: usize) -> f64 {
    f64::from_le_bytes(b[at..at + 8].try_into().unwrap())
}

impl State {
    /// Queues a question once per (kind, pointer).
    fn ask(&mut self, kind: u8, ptr: u64) {
        if ptr != 0 && self.asked.insert((kind, ptr)) {
            self.to_ask.push_back((kind, ptr));
        }
    }

    /// Sends queued questions, a few at a time (the client answers each in turn).
    fn send_queries(&mut self, stream: &mut TcpStream) -> Result<(), String> {
        while self.outstanding < 32 {
            let Some((kind, ptr)) = self.to_ask.pop_front() else {
                break;
            };
            if kind == query::SOURCE_LOCATION {
                self.source_location_answers.push_back(ptr);
            }
            stream
                .write_all(&query_packet(kind, ptr))
                .map_err(|e| format!("sending a query: {e}"))?;
            self.outstanding += 1;
        }
        Ok(())
    }

    fn answered(&mut self) {
        self.outstanding = self.outstanding.saturating_sub(1);
    }

    /// Reads the whole events at the start of `bytes`; returns how many bytes they took.
    fn read_events(&mut self, bytes: &[u8]) -> Result<usize, String> {
        let mut at = 0;
        while at < bytes.len() {
            let kind = bytes[at];
            if kind >= event::COUNT {
                return Err(format!("unknown event type {kind} at byte {at}"));
            }
            let size = protocol::EVENT_SIZE[kind as usize] as usize;
            let (trailing, length_bytes) = match protocol::trailer(kind) {
                Trailer::None => (0, 0),
                Trailer::Length { bytes: n, offset } => {
                    if at + size + n > bytes.len() {
                        break;
                    }
                    let length = match n {
                        1 => bytes[at + size] as usize,
                        2 => u16_at(bytes, at + size) as usize,
                        _ => u32_at(bytes, at + size) as usize,
                    };
                    (length + offset, n)
                }
            };
            let end = at + size + length_bytes + trailing;
            if end > bytes.len() {
                break;
            }
            let body = &bytes[at..at + size];
            let data = &bytes[at + size + length_bytes..end];
            self.event(kind, body, data)?;
            at = end;
        }
        Ok(at)
    }

    /// One event: `body` is its fixed part (type byte first), `data` the bytes it carries.
    fn event(&mut self, kind: u8, body: &[u8], data: &[u8]) -> Result<(), String> {
        use event::*;
        match kind {
            THREAD_CONTEXT => {
                self.thread = u32_at(body, 1);
                self.thread_time = 0;
                // Asked only once the client has terminated, as a profiler reading a
                // finished capture finds them: a thread that has ended by then is known only
                // by the name it told Tracy (its OS name is gone), so a short-lived thread
                // that did not is caught every time, not only when it ends first.
                if !self.threads_to_name.contains(&self.thread) {
                    self.threads_to_name.push(self.thread);
                }
            }
            ZONE_BEGIN | ZONE_BEGIN_CALLSTACK => self.zone_begin(
                full_delta(i64_at(body, 1)),
                ZoneName::Static(u64_at(body, 9)),
            ),
            ZONE_BEGIN_32 | ZONE_BEGIN_CALLSTACK_32 => self.zone_begin(
                u32_at(body, 1) as i64 + protocol::TIME_OFFSET_32,
                ZoneName::Static(u64_at(body, 5)),
            ),
            ZONE_BEGIN_16 | ZONE_BEGIN_CALLSTACK_16 => {
                self.zone_begin(u16_at(body, 1) as i64, ZoneName::Static(u64_at(body, 3)))
            }
            ZONE_BEGIN_ALLOC_SRC_LOC | ZONE_BEGIN_ALLOC_SRC_LOC_CALLSTACK => {
                let name = self
                    .payload
                    .take()
                    .ok_or("an allocated zone without its payload")?;
                self.zone_begin(i64_at(body, 1), ZoneName::Sent(name));
            }
            ZONE_END | ZONE_END_32 | ZONE_END_16 => {
                let delta = match kind {
                    ZONE_END => full_delta(i64_at(body, 1)),
                    ZONE_END_32 => u32_at(body, 1) as i64 + protocol::TIME_OFFSET_32,
                    _ => u16_at(body, 1) as i64,
                };
                self.thread_time += delta;
                let thread = self.thread;
                match self.open.entry(thread).or_default().pop() {
                    Some(z) => self.zones[z].end = Some(self.thread_time),
                    None => self
                        .capture
                        .nesting_errors
                        .push(format!("a zone end without a begin on thread {thread}")),
                }
            }
            GPU_ZONE_BEGIN
            | GPU_ZONE_BEGIN_CALLSTACK
            | GPU_ZONE_BEGIN_SERIAL
            | GPU_ZONE_BEGIN_CALLSTACK_SERIAL => {
                self.gpu_zone_begin(body, ZoneName::Static(u64_at(body, 16)));
            }
            GPU_ZONE_BEGIN_ALLOC_SRC_LOC
            | GPU_ZONE_BEGIN_ALLOC_SRC_LOC_CALLSTACK
            | GPU_ZONE_BEGIN_ALLOC_SRC_LOC_SERIAL
            | GPU_ZONE_BEGIN_ALLOC_SRC_LOC_CALLSTACK_SERIAL => {
                let name = self
                    .payload
                    .take()
                    .ok_or("an allocated GPU zone without its payload")?;
                self.gpu_zone_begin(body, ZoneName::Sent(name));
            }
            GPU_ZONE_END | GPU_ZONE_END_SERIAL => {
                let (query_id, context) = (u16_at(body, 13), body[15]);
                // An end closes the innermost GPU zone open on its context.
                match self.open_gpu.entry(context).or_default().pop() {
                    Some(z) => {
                        self.gpu_queries.insert((context, query_id), (z, true));
                    }
                    None => self.capture.nesting_errors.push(format!(
                        "a GPU zone end without a begin on context {context}"
                    )),
                }
            }
            GPU_TIME => {
                self.gpu_time += i64_at(body, 1);
                let key = (body[11], u16_at(body, 9));
                let on_cpu = self.capture.gpu_contexts.get(&key.0).map(|c| {
                    let (gpu, cpu) = c.tie;
                    cpu as f64 * self.capture.timer_ns
                        + (self.gpu_time - gpu) as f64 * c.period_ns as f64
                });
                match self.gpu_queries.remove(&key) {
                    Some((z, false)) => {
                        self.capture.gpu_zones[z].begin = Some(self.gpu_time);
                        self.capture.gpu_zones[z].cpu_begin_ns = on_cpu;
                    }
                    Some((z, true)) => {
                        self.capture.gpu_zones[z].end = Some(self.gpu_time);
                        self.capture.gpu_zones[z].cpu_end_ns = on_cpu;
                    }
                    None => self.capture.stray_gpu_times += 1,
                }
            }
            GPU_NEW_CONTEXT => {
                let context = body[25];
                let entry = self.capture.gpu_contexts.entry(context).or_default();
                entry.period_ns = f32_at(body, 21);
                entry.tie = (i64_at(body, 9), i64_at(body, 1));
            }
            GPU_CONTEXT_NAME => {
                let name = self.single_string.take();
                self.capture.gpu_contexts.entry(body[1]).or_default().name = name;
            }
            GPU_CALIBRATION => {
                self.capture
                    .gpu_contexts
                    .entry(body[25])
                    .or_default()
                    .clock_ties += 1;
            }
            GPU_TIME_SYNC => {
                let context = self.capture.gpu_contexts.entry(body[17]).or_default();
                context.clock_ties += 1;
                context.tie = (i64_at(body, 1), i64_at(body, 9));
            }
            PLOT_DATA_INT | PLOT_DATA_FLOAT | PLOT_DATA_DOUBLE => {
                self.thread_time += i64_at(body, 9);
                let name = u64_at(body, 1);
                let value = match kind {
                    PLOT_DATA_INT => i64_at(body, 17) as f64,
                    PLOT_DATA_FLOAT => f32_at(body, 17) as f64,
                    _ => f64_at(body, 17),
                };
                self.plot_values.push((name, value));
                self.ask(query::PLOT_NAME, name);
            }
            FRAME_MARK_MSG => {
                if u64_at(body, 9) == 0 {
                    self.capture.frame_marks += 1;
                } else {
                    self.ask(query::FRAME_NAME, u64_at(body, 9));
                }
            }
            SOURCE_LOCATION => {
                self.answered();
                let ptr = self
                    .source_location_answers
                    .pop_front()
                    .ok_or("a source location nobody asked for")?;
                let location = SourceLocation {
                    name: u64_at(body, 1),
                    function: u64_at(body, 9),
                };
                self.source_locations.insert(ptr, location);
                self.ask(query::STRING, location.name);
                self.ask(query::STRING, location.function);
            }
            STRING_DATA => {
                self.answered();
                self.strings
                    .insert(u64_at(body, 1), String::from_utf8_lossy(data).into_owned());
            }
            THREAD_NAME => {
                self.answered();
                self.capture.thread_names.insert(
                    u64_at(body, 1) as u32,
                    String::from_utf8_lossy(data).into_owned(),
                );
            }
            PLOT_NAME => {
                self.answered();
                self.plot_names
                    .insert(u64_at(body, 1), String::from_utf8_lossy(data).into_owned());
            }
            FRAME_NAME | ACK_SERVER_QUERY_NOOP => self.answered(),
            SOURCE_LOCATION_PAYLOAD => {
                // color (4), line (4), function\0, file\0, then the name (possibly empty).
                let text = &data[8..];
                let mut parts = text.splitn(3, |&b| b == 0);
                let function = parts.next().unwrap_or_default();
                let _file = parts.next().unwrap_or_default();
                let name = parts.next().unwrap_or_default();
                let name = if name.is_empty() { function } else { name };
                self.payload = Some(String::from_utf8_lossy(name).into_owned());
            }
            SINGLE_STRING_DATA | SINGLE_STRING_DATA_8 => {
                self.single_string = Some(String::from_utf8_lossy(data).into_owned());
            }
            MESSAGE_APP_INFO => {
                self.single_string = None;
            }
            TERMINATE => {
                self.terminated = true;
                for thread in std::mem::take(&mut self.threads_to_name) {
                    self.ask(query::THREAD_STRING, thread as u64);
                }
            }
            CRASH | CRASH_REPORT => return Err("the client reported a crash".into()),
            _ => {}
        }
        Ok(())
    }

    fn zone_begin(&mut self, delta: i64, name: ZoneName) {
        self.thread_time += delta;
        if let ZoneName::Static(ptr) = name {
            self.ask(query::SOURCE_LOCATION, ptr);
        }
        self.zones.push(ZoneRecord {
            name,
            thread: self.thread,
            begin: self.thread_time,
            end: None,
        });
        let index = self.zones.len() - 1;
        self.open.entry(self.thread).or_default().push(index);
    }

    fn gpu_zone_begin(&mut self, body: &[u8], name: ZoneName) {
        let (query_id, context) = (u16_at(body, 13), body[15]);
        if let ZoneName::Static(ptr) = name {
            self.ask(query::SOURCE_LOCATION, ptr);
        }
        self.gpu_names.push(name);
        self.capture.gpu_zones.push(GpuZone {
            name: String::new(),
            context,
            begin: None,
            end: None,
            cpu_begin_ns: None,
            cpu_end_ns: None,
        });
        let zone = self.capture.gpu_zones.len() - 1;
        self.gpu_queries.insert((context, query_id), (zone, false));
        self.open_gpu.entry(context).or_default().push(zone);
    }

    fn name_of(&self, name: &ZoneName) -> String {
        match name {
            ZoneName::Sent(name) => name.clone(),
            ZoneName::Static(ptr) => match self.source_locations.get(ptr) {
                Some(location) => {
                    let named = if location.name != 0 {
                        location.name
                    } else {
                        location.function
                    };
                    self.strings
                        .get(&named)
                        .cloned()
                        .unwrap_or_else(|| format!("<string {named:#x}>"))
                }
                None => format!("<source location {ptr:#x}>"),
            },
        }
    }

    fn finish(mut self) -> Capture {
        for ZoneRecord {
            name,
            thread,
            begin,
            end,
        } in &self.zones
        {
            let name = self.name_of(name);
            let thread = self
                .capture
                .thread_names
                .get(thread)
                .cloned()
                .unwrap_or_else(|| format!("thread {thread}"));
            let ns = |t: i64| t as f64 * self.capture.timer_ns;
            self.capture.cpu_zones.push(CpuZone {
                name: name.clone(),
                thread: thread.clone(),
                begin_ns: ns(*begin),
                end_ns: end.map(ns),
            });
            *self.capture.zones.entry(name.clone()).or_default() += 1;
            self.capture
                .zone_threads
                .entry(name)
                .or_default()
                .insert(thread);
        }
        for (thread, open) in &self.open {
            if !open.is_empty() {
                self.capture
                    .nesting_errors
                    .push(format!("{} zones left open on thread {thread}", open.len()));
            }
        }
        for (context, open) in &self.open_gpu {
            if !open.is_empty() {
                self.capture.nesting_errors.push(format!(
                    "{} GPU zones left open on context {context}",
                    open.len()
                ));
            }
        }
        for (z, name) in self.gpu_names.iter().enumerate() {
            self.capture.gpu_zones[z].name = self.name_of(name);
        }
        for (ptr, value) in &self.plot_values {
            let name = self
                .plot_names
                .get(ptr)
                .cloned()
                .unwrap_or_else(|| format!("<plot {ptr:#x}>"));
            self.capture.plots.entry(name).or_default().push(*value);
        }
        self.capture
    }
}
