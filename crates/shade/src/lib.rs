//! Images of captures: depth-complexity heat maps and nearest-layer depth, as PNG.
