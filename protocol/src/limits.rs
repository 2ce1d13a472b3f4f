//! Sizes beyond which a message is refused with `too_large` / `out_of_range`.

/// Largest accepted text message, in bytes.
pub const MAX_MESSAGE_BYTES: usize = 256 * 1024;
/// Longest name, token, sensor id or commit message, in bytes.
pub const MAX_STRING_BYTES: usize = 1024;
/// Most control points in a curve icon's (u,v) curve.
pub const MAX_CURVE_POINTS: usize = 256;
/// Most knots in any knot vector sent by a client.
pub const MAX_KNOTS: usize = 1024;
/// Most glove flexion values in one device sample.
pub const MAX_FLEXION: usize = 32;
/// Most sensors bound to one icon.
pub const MAX_SENSORS_PER_ICON: usize = 16;
/// Largest control grid (each direction) a frame may carry.
pub const MAX_GRID: usize = 2048;
/// Most icons a frame may carry.
pub const MAX_FRAME_ICONS: usize = 65_536;
/// Longest comment or reply text, in bytes of UTF-8 (about a page).
pub const MAX_COMMENT_BYTES: usize = 4096;
/// Most comments and replies one design may hold (the server may be
/// configured lower); more are refused with `too_large`.
pub const MAX_COMMENTS_PER_DESIGN: usize = 2000;
/// Largest magnitude accepted for a coordinate or material parameter.
pub const MAX_MAGNITUDE: f64 = 1e9;

/// Sustained rate of control messages (everything but `drag`,
/// `device_sample` and `presence`) one connection may send, per second.
pub const CONTROL_RATE: u32 = 100;
/// Control messages one connection may send in a burst above
/// [`CONTROL_RATE`].
pub const CONTROL_BURST: u32 = 200;
/// Sustained rate of stream messages (`drag`, `device_sample`, `presence`)
/// one connection may send, per second: far above any device or display.
pub const STREAM_RATE: u32 = 1000;
/// Stream messages one connection may send in a burst above [`STREAM_RATE`].
pub const STREAM_BURST: u32 = 1000;
/// Most `rate_limited` errors one connection gets per second (the rest of
/// its excess messages are dropped without a reply).
pub const RATE_LIMITED_ERRORS_PER_SEC: u32 = 10;
