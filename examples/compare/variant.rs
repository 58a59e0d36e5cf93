//! The candidate settings of `minimize` that `PLATEAU_FREE_VARIANT` selects.

/// Candidate settings of `minimize`, for `docs/convergence.md`: `PLATEAU_FREE_VARIANT` holds
/// comma-separated `key=value` pairs (`mirrored=1`, `flat=0`, `metric=full|diagonal`,
/// `sigma0=X`, `restarts=0`, `population=K`, `patience=K`, `target=X`, with `-inf` for no
/// target). Unset, the defaults.
pub fn variant<F: plateau_free::Objective>(
    mut m: plateau_free::Minimizer<F>,
) -> plateau_free::Minimizer<F> {
    let Ok(spec) = std::env::var("PLATEAU_FREE_VARIANT") else {
        return m;
    };
    for kv in spec.split(',').filter(|s| !s.is_empty()) {
        let (k, v) = kv.split_once('=').unwrap_or((kv, "1"));
        m = match k {
            "mirrored" => m.mirrored(v == "1"),
            "flat" => m.flat_growth(v == "1"),
            "restarts" => m.restarts(v == "1"),
            "from_best" => m.restart_from_best(v == "1"),
            "sigma0" => m.sigma0(v.parse().expect("sigma0")),
            "population" => m.population(v.parse().expect("population")),
            "patience" => m.patience(v.parse().expect("patience")),
            "target" => m.target(v.parse().expect("target")),
            "metric" => m.metric(match v {
                "full" => plateau_free::run::Metric::Full,
                "diagonal" => plateau_free::run::Metric::Diagonal,
                _ => plateau_free::run::Metric::Auto,
            }),
            other => panic!("unknown PLATEAU_FREE_VARIANT key {other}"),
        };
    }
    m
}
