//! Fits the default data with the default calibration settings, from the
//! current model defaults (or with `tangential_stiffness` given as argument).
use echothigh_contact::calibration::*;
fn main() {
    let data =
        IndentationCurve::from_path(std::path::Path::new("data/indentation-default.csv")).unwrap();
    let mut cal = Calibration::default();
    if let Some(t) = std::env::args().nth(1) {
        cal.model.tissue.tangential_stiffness = t.parse().unwrap();
    }
    let t0 = std::time::Instant::now();
    let rep = calibrate(&cal, &data).unwrap();
    println!(
        "{:?}\n{:?}\nrms {} max {} it {} ev {} {:?} in {:?}",
        rep.fitted,
        rep.tissue,
        rep.rms,
        rep.max_abs,
        rep.iterations,
        rep.evaluations,
        rep.termination,
        t0.elapsed()
    );
    for (d, f) in data.depth.iter().zip(&data.force) {
        println!(
            "{:.1} {:.3} {:.3}",
            d * 1e3,
            f,
            rep.model_curve.force_at(*d)
        );
    }
}
