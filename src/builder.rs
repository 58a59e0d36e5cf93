//! The builder methods that set one option each, written once.

/// Builder methods that each set one field and hand the builder back:
///
/// ```text
/// setters! {
///     /// The seed.
///     seed(seed: u64) => options.seed = seed;
///     /// The budget.
///     budget(budget: usize) => options.budget = Some(budget);
///     /// The box.
///     bounds(lower: Vec<f64>, upper: Vec<f64>) => options.bounds = Some((lower, upper));
/// }
/// ```
///
/// gives `#[must_use] pub fn seed(mut self, seed: u64) -> Self { self.options.seed = seed;
/// self }` and likewise for the others, each with its documentation. A method that checks
/// its value or sets more than one field is written out by hand instead.
macro_rules! setters {
    (
        $($(#[$attr:meta])* $name:ident($($arg:ident: $ty:ty),+) => $($field:ident).+ = $value:expr;)*
    ) => {
        $(
            $(#[$attr])*
            #[must_use]
            pub fn $name(mut self, $($arg: $ty),+) -> Self {
                self.$($field).+ = $value;
                self
            }
        )*
    };
}
