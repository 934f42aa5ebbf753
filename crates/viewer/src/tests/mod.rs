//! Tests of the viewer: the protocol (encoding, decoding, refusal of bad
//! page messages), the state message's JSON as the page reads it, and the
//! server end to end over a real WebSocket.

mod device;
mod display;
mod doppler;
mod image_link;
mod pace;
mod protocol;
mod resume;
mod server;
mod state_json;
