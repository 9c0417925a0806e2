//! The demo page's program (WebAssembly, `wasm32-wasip1`): a request on standard input, the
//! answer on standard output.
//!
//! Request: one line of JSON, `{"shape": NAME, "cells": N}` or `{"npy": true}` followed by the
//! `.npy` file's bytes. Answer: one JSON object, `{"summary": .., "rfta_page": .., "mc_page":
//! ..}` ([`rfta_web::Outcome`]) or `{"error": TEXT}`.

use std::io::{Read, Write};

fn answer(request: &[u8]) -> serde_json::Value {
    let line_end = request
        .iter()
        .position(|&b| b == b'\n')
        .unwrap_or(request.len());
    let head: serde_json::Value = match serde_json::from_slice(&request[..line_end]) {
        Ok(v) => v,
        Err(e) => return serde_json::json!({ "error": format!("bad request: {e}") }),
    };
    let input = if head["npy"] == true {
        rfta_web::Input::Npy(request.get(line_end + 1..).unwrap_or_default().to_vec())
    } else {
        rfta_web::Input::Shape {
            name: head["shape"].as_str().unwrap_or_default().to_string(),
            cells: head["cells"].as_u64().unwrap_or(0) as usize,
        }
    };
    match rfta_web::run(&input) {
        Ok(out) => serde_json::json!({
            "summary": out.summary,
            "rfta_page": out.rfta_page,
            "mc_page": out.mc_page,
        }),
        Err(e) => serde_json::json!({ "error": e }),
    }
}

fn main() {
    let mut request = Vec::new();
    let reply = match std::io::stdin().read_to_end(&mut request) {
        Ok(_) => answer(&request),
        Err(e) => serde_json::json!({ "error": format!("cannot read the request: {e}") }),
    };
    let mut out = std::io::stdout().lock();
    let _ = out.write_all(reply.to_string().as_bytes());
    let _ = out.flush();
}
