//! The `dump_parse` target: arbitrary bytes as a dump (`docs/dump-format.md`) through
//! [`Dump::parse`], never a panic. The input is a [`Blob`]: the header text up to the first NUL
//! byte; after it, each array file the parser asks for takes the next chunk
//! (`tools/fuzz/seed.py` writes a dump directory so). Checked: the parser only ever asks for
//! plain file names; a dump it accepts encodes and parses back to itself; decoding its words
//! ([`Dump::capture`], any layout: slots, A-buffer, linked lists with arbitrary links and
//! counters, layer-major layers, a scheme's memory, masked nodes; at any sample count the header
//! may name, one list a sample, or a pixel for masked nodes), checking them ([`Dump::check_words`]) and
//! comparing them with an oracle made of them either works, with one list
//! per pixel of the viewport, or fails with an error.

use fragsim::capture::{Capture, Keeps};
use fragsim::dump::{Dump, DumpError};
use fragsim::oracle::compare::compare;
use fragsim::oracle::Oracle;

use super::input::Input;

/// The name errors give the header.
const NAME: &str = "fuzz/dump.json";

/// A dump as the fuzzer's bytes hold it: the header text up to the first NUL byte, then one chunk
/// per array file the parser asks for (a little-endian `u16` length, then that many bytes, cut
/// short where the input ends).
pub(crate) struct Blob<'a> {
    /// The header's bytes.
    pub header: &'a [u8],
    input: Input<'a>,
    remaining: usize,
}

impl<'a> Blob<'a> {
    /// The dump `data` holds.
    pub(crate) fn new(data: &'a [u8]) -> Self {
        let (header, rest) = match data.iter().position(|&b| b == 0) {
            Some(nul) => (&data[..nul], &data[nul + 1..]),
            None => (data, &[][..]),
        };
        Self {
            header,
            input: Input::new(rest),
            remaining: rest.len(),
        }
    }

    /// The next chunk, as the bytes of array file `file`, which must be a plain file name.
    pub(crate) fn file(&mut self, file: &str) -> Vec<u8> {
        assert!(
            !file.is_empty() && file != ".." && !file.contains(['/', '\\']),
            "the parser asked for {file:?}, not a plain file name"
        );
        let len = usize::from(u16::from_le_bytes([self.input.u8(), self.input.u8()]));
        self.remaining = self.remaining.saturating_sub(2);
        let len = len.min(self.remaining);
        self.remaining -= len;
        (0..len).map(|_| self.input.u8()).collect()
    }
}

/// Whether a capture is what it promises of itself: lists in canonical order, no overflow (with
/// overflow it claims fragments that its own lists lack).
pub(crate) fn is_canonical(capture: &Capture) -> bool {
    let no_overflow = match &capture.keeps {
        Keeps::All { overflow, .. } => overflow.iter().all(|&o| o == 0),
        _ => true,
    };
    no_overflow && (0..capture.pixels()).all(|p| capture.pixel(p).windows(2).all(|w| w[0] <= w[1]))
}

/// Parses `data` as a dump and checks the outcome.
pub(crate) fn check(data: &[u8]) {
    let mut blob = Blob::new(data);
    let header = blob.header;
    let Ok(dump) = Dump::parse(NAME, header, |file| Ok(blob.file(file))) else {
        return;
    };
    let (text, files) = dump.encode().expect("a parsed dump encodes");
    let again = Dump::parse(NAME, text.as_bytes(), |file| {
        files
            .get(file)
            .cloned()
            .ok_or_else(|| DumpError::Invalid(format!("{file} was not encoded")))
    })
    .expect("an encoded dump parses");
    assert_eq!(again, dump, "a dump differs after encoding and parsing");
    // The sample count (`scene.conventions.samples`): a parsed header's is a standard one, and
    // its lists are one a pixel (masked nodes) or one a sample (every other layout).
    let samples = dump
        .header
        .samples()
        .expect("parse refuses other sample counts");
    assert!(
        fragsim::raster::SamplePattern::COUNTS.contains(&samples),
        "{samples} is no standard sample count"
    );
    let pixels = dump
        .header
        .pixel_viewport()
        .expect("parse checked it")
        .pixels();
    let lists = if dump.is_masked() {
        pixels
    } else {
        pixels * samples as usize
    };
    assert_eq!(
        dump.viewport().expect("parse checked it").pixels(),
        lists,
        "lists per pixel and sample"
    );
    let Ok(capture) = dump.capture() else {
        return;
    };
    assert_eq!(capture.pixels(), lists, "one list per pixel and sample");
    // Every word rule runs on what decodes, linked lists whose links leave the pool or close a
    // cycle included (the walk is bounded by the pool: a hang is a fuzz timeout).
    let words = dump
        .check_words()
        .expect("a dump that decodes has its words checked");
    assert_eq!(words.corrupt.len(), lists, "one word check per list");
    if let Keeps::All { overflow, .. } = &capture.keeps {
        assert_eq!(overflow.len(), lists, "one overflow count per list");
    }
    let comparison = compare(&Oracle::from_capture(&capture), &capture, 0, 4);
    assert!(
        !is_canonical(&capture) || comparison.is_equal(),
        "a capture in canonical order differs from itself"
    );
}
