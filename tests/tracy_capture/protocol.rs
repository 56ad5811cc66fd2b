//! The few facts of Tracy's wire protocol that a capture needs, for the protocol of the
//! `tracy-client-sys` this workspace's `Cargo.lock` resolves (0.30.1, Tracy 0.14.1, protocol 82).
//! Written from the client's protocol headers (`common/TracyProtocol.hpp`, `TracyQueue.hpp`):
//! the event numbers below and each event's size on the wire (the client's `QueueDataSize`
//! table, printed by a program compiled against those headers). Another protocol version is
//! refused by the client's handshake, so a `tracy-client-sys` update fails the test loudly at the
//! handshake rather than misreading events.

/// The client's protocol version (`ProtocolVersion`).
pub const PROTOCOL_VERSION: u32 = 82;
/// Sent first by the server (`HandshakeShibboleth`).
pub const SHIBBOLETH: &[u8; 8] = b"TracyPrf";
/// The client's answer to a matching handshake (`HandshakeWelcome`).
pub const HANDSHAKE_WELCOME: u8 = 1;
/// Size of the client's `WelcomeMessage` (packed).
pub const WELCOME_SIZE: usize = 8 * 8 + 1 + 1 + 12 + 4 + 64 + 1024;
/// Offset of `programName` in the welcome message.
pub const WELCOME_PROGRAM_NAME: usize = 8 * 8 + 1 + 1 + 12 + 4;
/// The largest decompressed frame (`TargetFrameSize`).
pub const TARGET_FRAME_SIZE: usize = 256 * 1024;
/// How far back an LZ4 match may reach.
pub const LZ4_WINDOW: usize = 64 * 1024;
/// Added to a 16-bit string length of `SingleStringData`/`SecondStringData`
/// (`ProtocolOffset8Bit`).
pub const STRING_LENGTH_OFFSET: usize = 1 << 8;
/// Added to the 32-bit time differences of `ZoneBegin32` and `ZoneEnd32` (`ProtocolOffset16Bit`).
pub const TIME_OFFSET_32: i64 = 1 << 16;
/// Added to a non-negative 64-bit time difference of `ZoneBegin` and `ZoneEnd`: the client sends
/// there only differences past the 32-bit event's range (`ProtocolOffset32Bit`).
pub const TIME_OFFSET_64: i64 = (1 << 16) + (1 << 32);

/// `ServerQuery`: the server's requests, 13 bytes each (type, u64 pointer, u32 extra).
pub mod query {
    pub const TERMINATE: u8 = 0;
    pub const STRING: u8 = 1;
    pub const THREAD_STRING: u8 = 2;
    pub const SOURCE_LOCATION: u8 = 3;
    pub const PLOT_NAME: u8 = 4;
    pub const FRAME_NAME: u8 = 5;
}

/// `QueueType`: the first byte of every event.
pub mod event {
    pub const MESSAGE_APP_INFO: u8 = 6;
    pub const ZONE_BEGIN_ALLOC_SRC_LOC: u8 = 7;
    pub const ZONE_BEGIN_ALLOC_SRC_LOC_CALLSTACK: u8 = 8;
    pub const ZONE_BEGIN: u8 = 19;
    pub const ZONE_BEGIN_32: u8 = 20;
    pub const ZONE_BEGIN_16: u8 = 21;
    pub const ZONE_BEGIN_CALLSTACK: u8 = 22;
    pub const ZONE_BEGIN_CALLSTACK_32: u8 = 23;
    pub const ZONE_BEGIN_CALLSTACK_16: u8 = 24;
    pub const ZONE_END: u8 = 25;
    pub const ZONE_END_32: u8 = 26;
    pub const ZONE_END_16: u8 = 27;
    pub const GPU_ZONE_BEGIN: u8 = 45;
    pub const GPU_ZONE_BEGIN_CALLSTACK: u8 = 46;
    pub const GPU_ZONE_BEGIN_ALLOC_SRC_LOC: u8 = 47;
    pub const GPU_ZONE_BEGIN_ALLOC_SRC_LOC_CALLSTACK: u8 = 48;
    pub const GPU_ZONE_END: u8 = 49;
    pub const GPU_ZONE_BEGIN_SERIAL: u8 = 50;
    pub const GPU_ZONE_BEGIN_CALLSTACK_SERIAL: u8 = 51;
    pub const GPU_ZONE_BEGIN_ALLOC_SRC_LOC_SERIAL: u8 = 52;
    pub const GPU_ZONE_BEGIN_ALLOC_SRC_LOC_CALLSTACK_SERIAL: u8 = 53;
    pub const GPU_ZONE_END_SERIAL: u8 = 54;
    pub const PLOT_DATA_INT: u8 = 55;
    pub const PLOT_DATA_FLOAT: u8 = 56;
    pub const PLOT_DATA_DOUBLE: u8 = 57;
    pub const GPU_TIME: u8 = 60;
    pub const GPU_CONTEXT_NAME: u8 = 61;
    pub const TERMINATE: u8 = 73;
    pub const THREAD_CONTEXT: u8 = 75;
    pub const GPU_CALIBRATION: u8 = 76;
    pub const GPU_TIME_SYNC: u8 = 77;
    pub const CRASH: u8 = 78;
    pub const CRASH_REPORT: u8 = 79;
    pub const FRAME_MARK_MSG: u8 = 83;
    pub const SOURCE_LOCATION: u8 = 87;
    pub const GPU_NEW_CONTEXT: u8 = 95;
    pub const ACK_SERVER_QUERY_NOOP: u8 = 108;
    pub const SINGLE_STRING_DATA: u8 = 112;
    pub const SECOND_STRING_DATA: u8 = 113;
    pub const SINGLE_STRING_DATA_8: u8 = 114;
    pub const SECOND_STRING_DATA_8: u8 = 115;
    /// The first of the events followed by a length and that many bytes (`QueueStringTransfer`).
    pub const STRING_DATA: u8 = 119;
    pub const THREAD_NAME: u8 = 120;
    pub const PLOT_NAME: u8 = 121;
    pub const SOURCE_LOCATION_PAYLOAD: u8 = 122;
    pub const FRAME_NAME: u8 = 125;
    pub const FRAME_IMAGE_DATA: u8 = 126;
    pub const SYMBOL_CODE: u8 = 129;
    pub const SOURCE_CODE: u8 = 130;
    /// One past the last event type (`NUM_TYPES`).
    pub const COUNT: u8 = 132;
}

/// Each event's size on the wire, its type byte included, before any string it carries
/// (`QueueDataSize`, indexed by event type).
pub const EVENT_SIZE: [u8; event::COUNT as usize] = [
    1, 1, 10, 13, 10, 13, 9, 9, 9, 1, 1, 1, 13, 9, 7, 13, 9, 7, 10, 17, 13, 11, 17, 13, 11, 9, 5,
    3, 17, 17, 13, 17, 17, 17, 5, 27, 27, 21, 21, 27, 27, 21, 21, 21, 21, 24, 24, 16, 16, 16, 24,
    24, 16, 16, 16, 25, 21, 25, 23, 16, 12, 2, 10, 10, 13, 1, 1, 1, 25, 13, 15, 13, 3, 1, 1, 5, 26,
    18, 1, 17, 5, 4, 9, 17, 17, 17, 13, 32, 22, 13, 17, 17, 20, 17, 20, 28, 17, 13, 25, 17, 17, 17,
    17, 17, 17, 17, 16, 18, 1, 5, 1, 17, 1, 1, 1, 1, 9, 9, 24, 9, 9, 9, 9, 9, 9, 9, 9, 9, 9, 9, 9,
    9,
];

/// How an event's trailing bytes are counted: none, or a length of this many bytes (plus
/// [`STRING_LENGTH_OFFSET`] where `offset`) followed by that many bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Trailer {
    None,
    Length { bytes: usize, offset: usize },
}

/// The trailer of each event type.
pub fn trailer(kind: u8) -> Trailer {
    use event::*;
    match kind {
        SINGLE_STRING_DATA | SECOND_STRING_DATA => Trailer::Length {
            bytes: 2,
            offset: STRING_LENGTH_OFFSET,
        },
        SINGLE_STRING_DATA_8 | SECOND_STRING_DATA_8 => Trailer::Length {
            bytes: 1,
            offset: 0,
        },
        FRAME_IMAGE_DATA | SYMBOL_CODE | SOURCE_CODE => Trailer::Length {
            bytes: 4,
            offset: 0,
        },
        k if k >= STRING_DATA => Trailer::Length {
            bytes: 2,
            offset: 0,
        },
        _ => Trailer::None,
    }
}
