//! What a walk starts from ([`Scheme::Input`](crate::Scheme::Input)): the rasterizer's fragment
//! for every scheme but one, or what a scheme gathers from a triangle's fragments first.
//!
//! A GPU's fragment shader runs once per pixel a primitive covers. Without multisampling that is
//! one rasterized fragment; under multisampling without per-sample shading it is one invocation
//! for all the samples the primitive covers in the pixel, which it sees as a coverage mask. The
//! masked-node A-buffer (`schemes/masked_abuffer.rs`) is written for the second case: its walk
//! starts from a primitive's samples in one pixel, merged. The executors feed every scheme the
//! same way, through [`WalkInput::gather`] and [`WalkInput::flush`]: the rasterizer's fragments,
//! a triangle's one after another, go in, and the walks' inputs come out. For a [`Fragment`]
//! gathering is the identity and compiles away.

use std::fmt::Debug;

use fragsim_raster::Fragment;

/// What one walk of a scheme starts from, and how a stream of the rasterizer's fragments becomes
/// such inputs.
pub trait WalkInput: Copy + Send + Sync + Debug + 'static {
    /// What a thread keeps between fragments while it gathers them into inputs (nothing, for
    /// a [`Fragment`]); a scheme hands out a fresh one ([`Scheme::gathering`](crate::Scheme::gathering)).
    type Gathering: Default + Send;

    /// Takes the rasterizer's next `fragment` (a triangle's fragments come one after another,
    /// triangle after triangle) and hands every input it completes to `emit`.
    fn gather(gathering: &mut Self::Gathering, fragment: Fragment, emit: &mut impl FnMut(Self));

    /// The end of a stream: hands what `gathering` still holds to `emit`.
    fn flush(gathering: &mut Self::Gathering, emit: &mut impl FnMut(Self));

    /// The index of the storage pixel the walk writes (a trace's pixel, a stuck lane's).
    fn pixel(self) -> u32;
}

impl WalkInput for Fragment {
    type Gathering = ();

    #[inline]
    fn gather((): &mut (), fragment: Fragment, emit: &mut impl FnMut(Self)) {
        emit(fragment);
    }

    #[inline]
    fn flush((): &mut (), _: &mut impl FnMut(Self)) {}

    #[inline]
    fn pixel(self) -> u32 {
        self.pixel
    }
}

/// The inputs `scheme` walks for `fragments`, a stream of the rasterizer's (a triangle's
/// fragments one after another): the fragments themselves for a scheme that walks fragments.
pub fn inputs_of<S: crate::Scheme + ?Sized>(
    scheme: &S,
    fragments: impl IntoIterator<Item = Fragment>,
) -> Vec<S::Input> {
    let mut inputs = Vec::new();
    let mut gathering = scheme.gathering();
    for fragment in fragments {
        S::Input::gather(&mut gathering, fragment, &mut |input| inputs.push(input));
    }
    S::Input::flush(&mut gathering, &mut |input| inputs.push(input));
    inputs
}
