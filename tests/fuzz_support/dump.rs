//! The `dump_parse` target: arbitrary bytes as a dump (`docs/dump-format.md`) through
//! [`Dump::parse`], never a panic. The input is the header text up to the first NUL byte; after
//! it, each array file the parser asks for takes the next chunk (a little-endian `u16` length,
//! then that many bytes, cut short where the input ends). Checked: the parser only ever asks for
//! plain file names; a dump it accepts encodes and parses back to itself; decoding its words
//! ([`Dump::capture`], any layout: slots, A-buffer, linked lists with arbitrary links and
//! counters, layer-major layers, a scheme's memory), checking them ([`Dump::check_words`]) and
//! comparing them with an oracle made of them either works, with one list
//! per pixel of the viewport, or fails with an error.

use fragsim::capture::Keeps;
use fragsim::oracle::compare::compare;
use fragsim::oracle::dump::{Dump, DumpError};
use fragsim::oracle::Oracle;

use super::input::Input;

/// The name errors give the header.
const NAME: &str = "fuzz/dump.json";

/// Parses `data` as a dump and checks the outcome.
pub fn check(data: &[u8]) {
    let (header, rest) = match data.iter().position(|&b| b == 0) {
        Some(nul) => (&data[..nul], &data[nul + 1..]),
        None => (data, &[][..]),
    };
    let mut input = Input::new(rest);
    let mut remaining = rest.len();
    let read_file = |file: &str| -> Result<Vec<u8>, DumpError> {
        assert!(
            !file.is_empty() && file != ".." && !file.contains(['/', '\\']),
            "the parser asked for {file:?}, not a plain file name"
        );
        let len = usize::from(u16::from_le_bytes([input.u8(), input.u8()]));
        remaining = remaining.saturating_sub(2);
        let len = len.min(remaining);
        remaining -= len;
        Ok((0..len).map(|_| input.u8()).collect())
    };
    let Ok(dump) = Dump::parse(NAME, header, read_file) else {
        return;
    };
    let (text, files) = dump.encode().expect("a parsed dump encodes");
    let again = Dump::parse(NAME, text.as_bytes(), |file| {
        files
            .get(file)
            .cloned()
            .ok_or_else(|| DumpError(format!("{file} was not encoded")))
    })
    .expect("an encoded dump parses");
    assert_eq!(again, dump, "a dump differs after encoding and parsing");
    let Ok(capture) = dump.capture() else {
        return;
    };
    let pixels = dump.viewport().expect("parse checked it").pixels();
    assert_eq!(capture.pixels(), pixels, "one list per pixel");
    // Every word rule runs on what decodes, linked lists whose links leave the pool or close a
    // cycle included (the walk is bounded by the pool: a hang is a fuzz timeout).
    let words = dump
        .check_words()
        .expect("a dump that decodes has its words checked");
    assert_eq!(words.corrupt.len(), pixels, "one word check per pixel");
    if let Keeps::All { overflow, .. } = &capture.keeps {
        assert_eq!(overflow.len(), pixels, "one overflow count per pixel");
    }
    // A capture whose lists are in canonical order, with no overflow, is what it promises of
    // itself (with overflow it claims fragments that its own lists lack).
    let reference = Oracle::from_capture(&capture);
    let comparison = compare(&reference, &capture, 0, 4);
    let no_overflow = match &capture.keeps {
        Keeps::All { overflow, .. } => overflow.iter().all(|&o| o == 0),
        _ => true,
    };
    let in_order =
        no_overflow && (0..pixels).all(|p| capture.pixel(p).windows(2).all(|w| w[0] <= w[1]));
    assert!(
        !in_order || comparison.is_equal(),
        "a capture in canonical order differs from itself"
    );
}
