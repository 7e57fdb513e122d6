//! A model file that loads means one thing: a hand-edited or foreign file whose inputs or
//! responses are named twice, whose domains are no intervals or that has nothing to predict is
//! refused with the field named, instead of predicting from the wrong column.

use mbgc::metamodel::Metamodel;
use serde_json::{json, Value};

fn tiny() -> Value {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/tiny_model.json"
    ))
    .unwrap();
    serde_json::from_str(&text).unwrap()
}

fn load(v: &Value) -> Result<Metamodel, String> {
    Metamodel::from_json_str(&v.to_string(), "m.json").map_err(|e| e.to_string())
}

#[test]
fn the_shipped_files_still_load() {
    load(&tiny()).unwrap();
    for f in [
        "shear_box",
        "diagnose_local",
        "diagnose_local_sjkr",
        "shear_box_cohesion_local",
    ] {
        let path = format!("{}/models/{f}.json", env!("CARGO_MANIFEST_DIR"));
        Metamodel::load(std::path::Path::new(&path)).unwrap();
    }
}

/// An edit of a model file.
type Edit = Box<dyn Fn(&mut Value)>;

#[test]
fn broken_models_are_refused_by_field() {
    let edits: Vec<(&str, Edit, &str)> = vec![
        (
            "an input named twice",
            Box::new(|m| m["inputs"][1]["name"] = json!("x")),
            "inputs[1].name",
        ),
        (
            "a response named twice",
            Box::new(|m| {
                let r = m["responses"][0].clone();
                m["responses"].as_array_mut().unwrap().push(r);
            }),
            "responses[1].name",
        ),
        (
            "an empty response name",
            Box::new(|m| m["responses"][0]["name"] = json!("")),
            "responses[0].name",
        ),
        (
            "a domain [1, 0]",
            Box::new(|m| m["inputs"][0]["domain"] = json!([1.0, 0.0])),
            "inputs.x.domain",
        ),
        (
            "no responses",
            Box::new(|m| m["responses"] = json!([])),
            "responses",
        ),
        (
            "a response that is an input",
            Box::new(|m| m["responses"][0]["name"] = json!("z")),
            "responses.z",
        ),
        (
            "a negative box scale",
            Box::new(|m| m["box_scale"] = json!(-3.0)),
            "box_scale",
        ),
        (
            "an unknown experiment",
            Box::new(|m| m["experiment"] = json!("warp-drive")),
            "experiment",
        ),
    ];
    for (what, edit, field) in edits {
        let mut m = tiny();
        edit(&mut m);
        let e = load(&m).expect_err(what);
        assert!(e.contains("m.json") && e.contains(field), "{what}: {e}");
    }
}

/// A model's constraints: refused when they name something it does not have, measured as a
/// relative excess whose gradient matches finite differences, and kept through a save.
#[test]
fn constraints_are_checked_measured_and_kept() {
    let mut v = tiny();
    v["constraints"] = json!(["z <= 0.5*x + w"]);
    let e = load(&v).unwrap_err();
    assert!(e.contains("constraints[0]") && e.contains("\"w\""), "{e}");
    v["constraints"] = json!(["z <= 0.5*x"]);
    let m = load(&v).unwrap();
    assert_eq!(m.constraint_excess(&[0.8, 0.3]), 0.0);
    assert!(m.violated_constraint(&[0.8, 0.3]).is_none());
    assert_eq!(m.violated_constraint(&[0.4, 0.3]), Some("z <= 0.5*x"));
    // (0.3 - 0.2) / (0.3 + 0.2) = 0.2, squared.
    let x = [0.4, 0.3];
    let (e, g) = m.constraint_excess_with_gradient(&x);
    assert!(
        (e - 0.04).abs() < 1e-12 && (m.constraint_excess(&x) - e).abs() < 1e-15,
        "{e}"
    );
    for k in 0..2 {
        let h = 1e-7;
        let mut xp = x;
        xp[k] += h;
        let mut xm = x;
        xm[k] -= h;
        let fd = (m.constraint_excess(&xp) - m.constraint_excess(&xm)) / (2.0 * h);
        assert!((fd - g[k]).abs() < 1e-6, "d/dx{k}: {fd} vs {}", g[k]);
    }
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("m.json");
    m.save(&path).unwrap();
    let back = Metamodel::load(&path).unwrap();
    assert_eq!(back.constraints, ["z <= 0.5*x"]);
    assert_eq!(back.constraint_excess(&x), e);
}
