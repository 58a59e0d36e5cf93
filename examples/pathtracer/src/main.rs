//! The `pathtracer` command: the paper's inverse-rendering tasks on a CPU path tracer.
//!
//! ```text
//! cargo run --release -p pathtracer -- optimize shadow          # one task end to end
//! cargo run --release -p pathtracer -- render cup --target --out cup.png
//! cargo run --release -p pathtracer -- all                      # every task + baseline
//! ```

fn main() {
    pathtracer::cli::main();
}
