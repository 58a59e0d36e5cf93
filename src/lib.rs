//! plateau: usable gradients for black-box functions (work in progress).
