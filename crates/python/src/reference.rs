//! The oracle's lists and a verdict as numpy arrays and plain Python values: what crosses into
//! Python whole, never a pixel at a time.
//!
//! The reference is the oracle's flat storage as it is (each list's fragment words in canonical
//! order, `key << 32 | prim`, with counts and offsets), and with a K its K nearest per list laid
//! out as an MDTS dump's slots. A verdict crosses as its summary (the JSON `fragsim compare`
//! builds its report from), its one-word verdict, and its per-list flags, from which the Python
//! side finds the differing pixels with numpy.

use fragsim_oracle::compare::flags;
use fragsim_oracle::verdict::{SideReport, Verdict};
use fragsim_oracle::Oracle;
use numpy::{PyArray1, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::errors::JudgeError;

/// The empty slot of a K-nearest list: all ones, as MDTS leaves it.
const EMPTY: u64 = u64::MAX;

/// `oracle`'s lists as arrays (see `SceneCore::reference`).
pub(crate) fn reference_arrays<'py>(
    py: Python<'py>,
    oracle: &Oracle,
    k: Option<usize>,
) -> PyResult<Bound<'py, PyDict>> {
    let lists = oracle.pixels();
    let mut counts = Vec::with_capacity(lists);
    let mut offsets = Vec::with_capacity(lists + 1);
    let mut words = Vec::with_capacity(oracle.fragments());
    offsets.push(0_u64);
    for p in 0..lists {
        let list = oracle.pixel(p);
        #[expect(
            clippy::cast_possible_truncation,
            reason = "a pixel's list holds at most one fragment per triangle, and triangle ids are u32"
        )]
        counts.push(list.len() as u32);
        words.extend_from_slice(list);
        offsets.push(words.len() as u64);
    }
    let dict = PyDict::new(py);
    if let Some(k) = k {
        let mut nearest = vec![EMPTY; lists * k];
        for (p, slots) in nearest.chunks_exact_mut(k.max(1)).enumerate().take(lists) {
            let list = oracle.pixel(p);
            let kept = list.len().min(k);
            slots[..kept].copy_from_slice(&list[..kept]);
        }
        dict.set_item(
            "nearest",
            PyArray1::from_vec(py, nearest).reshape([lists, k])?,
        )?;
    }
    dict.set_item("counts", PyArray1::from_vec(py, counts))?;
    dict.set_item("offsets", PyArray1::from_vec(py, offsets))?;
    dict.set_item("words", PyArray1::from_vec(py, words))?;
    Ok(dict)
}

/// `verdict` as the Python side reads it: `equal`, `word` (`EQUAL (bit-identical)`, …,
/// `DIFFERENT`), `summary` (the report's JSON, its sides described as `reference` and
/// `candidate`), `flags` (uint8 per list: `fragsim_oracle::compare::flags`'s bits),
/// `reference_fragments` (uint32 per list), `width`, `height`, `lists_per_pixel`.
pub(crate) fn verdict_dict<'py>(
    py: Python<'py>,
    verdict: &Verdict,
    reference: SideReport,
    candidate: SideReport,
) -> PyResult<Bound<'py, PyDict>> {
    let summary = verdict.summary(reference, candidate);
    let json = serde_json::to_string(&summary).map_err(|e| JudgeError::new_err(e.to_string()))?;
    let dict = PyDict::new(py);
    dict.set_item("equal", verdict.equal)?;
    dict.set_item("word", summary.word())?;
    dict.set_item("summary", json)?;
    dict.set_item(
        "flags",
        PyArray1::from_vec(py, verdict.comparison.verdicts.clone()),
    )?;
    dict.set_item(
        "reference_fragments",
        PyArray1::from_vec(py, verdict.reference_fragments.clone()),
    )?;
    dict.set_item("width", verdict.width)?;
    dict.set_item("height", verdict.height)?;
    dict.set_item("lists_per_pixel", verdict.lists_per_pixel)?;
    Ok(dict)
}

/// The verdict flags by name (`missing`, `extra`, …, with `differs`: the flags that make a
/// list differ), as the per-list `flags` of a verdict hold them.
#[pyfunction]
pub fn verdict_flags() -> Vec<(&'static str, u8)> {
    flags::NAMES
        .iter()
        .map(|&(bit, name)| (name, bit))
        .chain([("differs", flags::DIFFERS)])
        .collect()
}
