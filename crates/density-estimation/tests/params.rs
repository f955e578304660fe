//! Bad parameter values are refused with the key named.

use radlab_density_estimation::DensityEstimationParams;
use radlab_method::MethodParams;

fn refused(key: &str, value: toml::Value) -> String {
    let mut t = toml::Table::new();
    t.insert(key.to_string(), value);
    match DensityEstimationParams::from_table(t) {
        Ok(_) => panic!("{key} accepted"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn bad_values_name_their_key() {
    for (key, value) in [
        ("bandwidth", toml::Value::Float(0.0)),
        ("bandwidth", toml::Value::Float(f64::NAN)),
        ("bandwidth_size", toml::Value::Float(-1.0)),
        ("group_angle", toml::Value::Float(90.0)),
        ("particles", toml::Value::Integer(0)),
        ("steps", toml::Value::Integer(0)),
        ("boundary", toml::Value::String("linear".into())),
        ("reconstruction", toml::Value::String("gouraud".into())),
        ("element_size", toml::Value::Float(0.0)),
    ] {
        let e = refused(key, value.clone());
        assert!(e.contains(key), "{key} = {value}: {e}");
    }
    let e = refused("kernel", toml::Value::String("epanechnikov".into()));
    assert!(e.contains("kernel") && e.contains("bandwidth"), "{e}");
    assert_eq!(
        DensityEstimationParams::from_table(toml::Table::new()).expect("defaults"),
        DensityEstimationParams::default()
    );
}
