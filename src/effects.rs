//! `mbgc effects`: the physical effects a model class can switch on, with their parameters
//! (names, units, allowed ranges), as a Markdown table (the guide's, docs/guide/src/dem-engine.md, is this output) or JSON.

use clap::Args;

use mbgc::dem::contact::{all_effects, EffectSpec, ModelClass, LIMIT_FORCE};
use mbgc_output::say;
use mbgc_output::Output;

#[derive(Debug, Args)]
pub struct EffectsArgs {
    /// Standard output holds one JSON object (the effects); text goes to standard error.
    #[arg(long)]
    pub json: bool,
}

fn number(x: f64) -> String {
    if x != 0.0 && !(1e-3..1e4).contains(&x.abs()) {
        format!("{x:e}")
    } else {
        format!("{x}")
    }
}

fn range(r: (f64, f64)) -> String {
    format!("[{}, {}]", number(r.0), number(r.1))
}

/// The Markdown table of every registered effect.
pub fn table() -> String {
    let mut t = String::from(
        "| slot | effect | parameters (particle-particle, particle-wall) | unit | allowed range | default | metamodel input | LIGGGHTS 3.8 |\n\
         |---|---|---|---|---|---|---|---|\n",
    );
    let default = ModelClass::default();
    let defaults = [
        default.normal.spec().name,
        default.tangential.spec().name,
        default.rolling.spec().name,
        default.cohesion.spec().name,
    ];
    for e in all_effects() {
        let name = if defaults.contains(&e.name) {
            format!("`{}` (default)", e.name)
        } else {
            format!("`{}`", e.name)
        };
        let cell = |f: &dyn Fn(&mbgc::dem::contact::ParamSpec) -> String| {
            e.params.iter().map(f).collect::<Vec<_>>().join("; ")
        };
        t += &format!(
            "| {} | {name}: {} | {} | {} | {} | {} | {} | {} |\n",
            e.slot.label(),
            e.what,
            cell(&|p| format!("`{}`, `{}`: {}", p.names[0], p.names[1], p.what)),
            cell(&|p| p.unit.to_string()),
            cell(&|p| range(p.range)),
            cell(&|p| p.default.map_or("required".into(), number)),
            cell(&|p| if p.variable { "yes" } else { "fixed" }.into()),
            e.liggghts.map_or("-".into(), |l| format!("`{l}`"))
        );
    }
    // F_n in the caps is the normal force before cohesion (the load pressing the contact).
    t += &format!(
        "| option | `{LIMIT_FORCE}`: keep Hertz's normal force from turning attractive, damping \
         re-solved so e stays the restitution | | | | | | `limitForce on` (without the re-solved damping) |\n"
    );
    t
}

fn json(e: &EffectSpec) -> serde_json::Value {
    serde_json::json!({
        "name": e.name,
        "slot": e.slot.label(),
        "what": e.what,
        "liggghts": e.liggghts,
        "parameters": e.params.iter().map(|p| serde_json::json!({
            "names": p.names,
            "unit": p.unit,
            "range": [p.range.0, p.range.1],
            "default": p.default,
            "variable": p.variable,
            "what": p.what,
        })).collect::<Vec<_>>(),
    })
}

pub fn run(a: &EffectsArgs) -> anyhow::Result<()> {
    let out = Output::new(a.json);
    say!(out, "{}", table().trim_end());
    say!(
        out,
        "default model class: {} (--model-class takes comma-separated effect names)",
        ModelClass::default()
    );
    out.object(&serde_json::json!({
        "default": ModelClass::default().to_string(),
        "effects": all_effects().into_iter().map(json).collect::<Vec<_>>(),
        "options": [LIMIT_FORCE],
    }))
}
