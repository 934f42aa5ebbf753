//! Tests of the viewer: the protocol (encoding, decoding, refusal of bad
//! page messages) and the server end to end over a real WebSocket.

mod protocol;
mod server;
