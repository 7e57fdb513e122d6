//! Extending a trained model (`mbgc train --extends OLD`) in two ways that keep OLD's runs
//! valid, alone or together:
//!
//! - **Adding an effect.** The new space is OLD's space plus the parameters of effects OLD's
//!   class lacks. OLD's runs were made with those effects switched off, so they are the new
//!   space's runs on its effect-off face (a cohesion or rolling friction of 0).
//! - **Widening a range.** A parameter's range grows on either side (same scale, not fixed):
//!   OLD's runs lie inside the old ranges, a part of the new box. This is how a model is carried
//!   to stiffer or softer materials than it was trained on (issue 40).
//!
//! Either way OLD's runs become the first rows of the new design and are copied into the new
//! tables instead of being run again, and the sequential design fills the rest of the space
//! around them, so the new runs go where the old ones left the space emptiest. Only the new rows
//! are simulated.
//!
//! The copy of an added effect's runs is a statistical, not a bitwise, equivalence: with
//! cohesion switched on at 0 the engine projects the stored rolling torque onto the tangent plane
//! (`dem::contact::law`), so a rerun drifts apart chaotically like a replicate with another
//! seed. Each copied line says where it came from in its `warnings` field.

use std::path::Path;

use crate::campaign::columns::backend_of;
use crate::campaign::table::{csv_line, is_campaign_header, read_table};
use crate::campaign::{Meta, Plan};
use crate::error::{write_atomic, Error, Result};
use crate::sampling::design::Design;
use crate::space::Space;
use mbgc_dem::contact::{ModelClass, Pair};

/// How a new space extends an old one.
#[derive(Debug, Clone, PartialEq)]
pub struct Extension {
    /// Effects the new class adds to the old one.
    pub added: Vec<String>,
    /// The new parameters with the value that switches their effect off: where the old runs lie.
    pub off_face: Vec<(String, f64)>,
    /// Old parameters whose range the new space widens, with the old range: the old runs lie
    /// inside it.
    pub widened: Vec<(String, [f64; 2])>,
}

impl Extension {
    /// Where the old runs lie in the new space, for notes and the copied lines' warnings:
    /// "without sjkr (ced_pp = 0)", "inside the old ranges E_p [2.5e6, 5e7]" or both.
    pub fn old_runs(&self) -> String {
        let mut parts = Vec::new();
        if !self.added.is_empty() {
            parts.push(format!(
                "without {} ({})",
                self.added.join(", "),
                self.off_face
                    .iter()
                    .map(|(n, v)| format!("{n} = {v}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            ));
        }
        if !self.widened.is_empty() {
            parts.push(format!(
                "inside the old ranges {}",
                self.widened
                    .iter()
                    .map(|(n, r)| format!("{n} [{:e}, {:e}]", r[0], r[1]))
                    .collect::<Vec<_>>()
                    .join(", ")
            ));
        }
        parts.join(", ")
    }
}

/// Checks that `new` (with class `new_class`) is `old` plus the parameters of effects `old_class`
/// lacks, each of which can be switched off by a value the new space holds, and with some of
/// `old`'s ranges widened. Everything else must be as it was: the old runs stay valid only if
/// nothing they were run at moved, and stay a space-filling part of the new design only if each
/// old range lies inside the new one on the same scale.
pub fn check(
    old: &Space,
    old_class: &ModelClass,
    new: &Space,
    new_class: &ModelClass,
    pairs: &[Pair],
) -> Result<Extension> {
    let src = &new.source;
    let dropped = old_class.missing_from(new_class);
    if !dropped.is_empty() {
        return Err(Error::input(
            src,
            "model.class",
            format!(
                "{new_class} lacks {} of the class {old_class} the old runs were made with: an \
                 extension adds effects and keeps every old one",
                dropped.join(", ")
            ),
        ));
    }
    let added: Vec<String> = new_class
        .missing_from(old_class)
        .into_iter()
        .map(String::from)
        .collect();
    let mut widened = Vec::new();
    for p in &old.parameters {
        let Some(q) = new.get(&p.name) else {
            return Err(Error::input(
                src,
                format!("parameters.{}", p.name),
                format!(
                    "missing; the old space {} has it and its runs depend on it: keep it as it was",
                    old.source
                ),
            ));
        };
        let same_range = q.min == p.min && q.max == p.max;
        let wider = q.min <= p.min && q.max >= p.max && p.fixed.is_none();
        if q.scale != p.scale || q.fixed != p.fixed || !(same_range || wider) {
            return Err(Error::input(
                src,
                format!("parameters.{}", p.name),
                format!(
                    "[{}, {}] ({:?}{}) where the old space {} has [{}, {}] ({:?}{}): an \
                     extension keeps an old parameter's scale and fixed value and may only \
                     widen its range, so that the old runs lie inside the new space",
                    q.min,
                    q.max,
                    q.scale,
                    q.fixed.map(|f| format!(", fixed {f}")).unwrap_or_default(),
                    old.source,
                    p.min,
                    p.max,
                    p.scale,
                    p.fixed.map(|f| format!(", fixed {f}")).unwrap_or_default(),
                ),
            ));
        }
        if !same_range {
            widened.push((p.name.clone(), [p.min, p.max]));
        }
    }
    if added.is_empty() && widened.is_empty() {
        return Err(Error::input(
            src,
            "model.class",
            format!(
                "{new_class} adds no effect to {old_class} and no range is wider than in the old \
                 space {}: nothing to extend; to add runs to the same space, train it again with \
                 a larger --n",
                old.source
            ),
        ));
    }
    let owned = new_class.parameters(pairs);
    let mut off_face = Vec::new();
    for q in new.parameters.iter().filter(|q| old.get(&q.name).is_none()) {
        let field = format!("parameters.{}", q.name);
        let Some((_, spec, effect)) = owned.iter().find(|(n, _, _)| *n == q.name) else {
            return Err(Error::input(
                src,
                field,
                format!(
                    "not in the old space {} and of no effect added to it ({}): the old runs \
                     do not say at which value they were made",
                    old.source,
                    added.join(", ")
                ),
            ));
        };
        let Some(off) = spec.off else {
            return Err(Error::input(
                src,
                field,
                format!(
                    "{} cannot be switched off by a value, so the old runs lie on no face of the \
                     new space",
                    effect.name
                ),
            ));
        };
        match q.fixed {
            Some(f) if f != off => {
                return Err(Error::input(
                    src,
                    field,
                    format!(
                        "fixed at {f}, but the old runs were made without {} (at {off}): fix it \
                         at {off} or give it a range that holds {off}",
                        effect.name
                    ),
                ))
            }
            None if !q.contains(off) => {
                return Err(Error::input(
                    src,
                    field,
                    format!(
                        "[{}, {}] does not hold {off}, the value at which {} is off and the old \
                         runs lie: widen the range to {off}",
                        q.min, q.max, effect.name
                    ),
                ))
            }
            _ => {}
        }
        off_face.push((q.name.clone(), off));
    }
    Ok(Extension {
        added,
        off_face,
        widened,
    })
}

/// The old design's rows in the new space: the old values unchanged (bit for bit, so that the old
/// tables' lines match them) and each new parameter at its off value.
pub fn project_design(
    old_design: &Path,
    old: &Space,
    new: &Space,
    ext: &Extension,
) -> Result<Design> {
    let d = Design::read(old_design, Some(old))?;
    let mut out = Design::empty(Some(new), new.dim());
    for row in &d.values {
        let phys: Vec<f64> = new
            .parameters
            .iter()
            .map(
                |q| match old.parameters.iter().position(|p| p.name == q.name) {
                    Some(i) => row[i],
                    None => ext
                        .off_face
                        .iter()
                        .find(|(n, _)| *n == q.name)
                        .map(|(_, v)| *v)
                        .expect("check() gives every new parameter an off value"),
                },
            )
            .collect();
        out.unit.push(&new.to_unit(&phys));
        out.values.push(phys);
    }
    Ok(out)
}

/// Copies the finished lines of the old table `old_table` into the new table `out` (which must
/// not exist yet) as the lines of `plan`'s rows with the same index: the row seed is the same
/// (same campaign seed), the inputs of the old line must equal the planned ones bit for bit, the
/// new parameters are at their off values in the plan, and the run id and model class are the
/// plan's. Returns the number of lines copied.
pub fn copy_table(old_table: &Path, plan: &Plan, out: &Path, ext: &Extension) -> Result<usize> {
    let file = old_table.display().to_string();
    let t = read_table(old_table)?;
    if !is_campaign_header(&t.header) {
        return Err(Error::input(
            &file,
            "header",
            "not a campaign table (run_id,row,status,seed,model_class first)",
        ));
    }
    if let Some((line, rec)) = t.records.first() {
        if let Some(b) =
            backend_of(&t.header, rec).filter(|b| Some(b) != plan.backend_field().as_ref())
        {
            return Err(Error::input(
                &file,
                format!("line {line}, column backend"),
                format!(
                    "runs of the {b} backend, but the extension runs its new rows with the {} \
                     backend: one table holds the runs of one code",
                    plan.settings.backend
                ),
            ));
        }
    }
    let header = plan.columns();
    let col = |name: &str| t.header.iter().position(|h| h == name);
    let mut lines = csv_line(&header)?;
    let mut copied = 0;
    for (line, rec) in &t.records {
        let field = |c: &str| format!("line {line}, column {c}");
        let row: usize = rec[1]
            .parse()
            .map_err(|_| Error::input(&file, field("row"), "expected a row number"))?;
        let Some(planned) = plan.rows.get(row) else {
            return Err(Error::input(
                &file,
                field("row"),
                format!(
                    "row {row} is beyond the {} rows of {}",
                    plan.rows.len(),
                    plan.design.display()
                ),
            ));
        };
        let seed: u64 = rec[3]
            .parse()
            .map_err(|_| Error::input(&file, field("seed"), "expected a seed"))?;
        if seed != planned.seed {
            return Err(Error::input(
                &file,
                field("seed"),
                format!(
                    "{seed}, but row {row} of the extension has the seed {}: extend with the old \
                     train's --seed",
                    planned.seed
                ),
            ));
        }
        let mut f: Vec<String> = vec![
            planned.run_id.clone(),
            row.to_string(),
            rec[2].to_string(),
            seed.to_string(),
            plan.model_class_label(),
        ];
        if let Some(b) = plan.backend_field() {
            f.push(b);
        }
        for (name, want) in planned.params.iter() {
            let v = match col(name) {
                Some(c) => {
                    let same = rec[c]
                        .parse::<f64>()
                        .is_ok_and(|v| v.to_bits() == want.to_bits());
                    if !same {
                        return Err(Error::input(
                            &file,
                            field(name),
                            format!(
                                "\"{}\", but row {row} of {} has {want:?}: the table does not \
                                 belong to the old design",
                                &rec[c],
                                plan.design.display()
                            ),
                        ));
                    }
                    rec[c].to_string()
                }
                None => format!("{want:?}"),
            };
            f.push(v);
        }
        for name in header.iter().skip(plan.identity_len() + plan.inputs.len()) {
            let mut v = col(name).map(|c| rec[c].to_string()).unwrap_or_else(|| {
                // A response the experiment gained since the old table was written: a done run
                // has no value of it (NaN), a failed one no cells at all.
                if plan.responses.iter().any(|r| r == name) && &rec[2] == "done" {
                    "NaN".to_string()
                } else {
                    String::new()
                }
            });
            if name == "warnings" {
                let note = format!(
                    "copied from {file} row {row}, run by {} {}",
                    &rec[4],
                    ext.old_runs()
                );
                v = if v.is_empty() {
                    note
                } else {
                    format!("{v}; {note}")
                };
            }
            f.push(v);
        }
        lines.extend(csv_line(&f)?);
        copied += 1;
    }
    if out.exists() {
        return Err(Error::input(
            out.display(),
            "file",
            "exists already: the old runs are copied into a new table only",
        ));
    }
    if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    }
    // The sidecar first: a table without one would be read as another campaign's.
    Meta::of(plan).write(out)?;
    write_atomic(out, &lines)?;
    Ok(copied)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn space(class: &str, extra: &str) -> Space {
        let text = format!(
            "name = \"t\"\n[model]\nclass = \"{class}\"\n[parameters]\n\
             mu_pp = {{ min = 0.2, max = 0.9 }}\nd50 = {{ min = 1, max = 20, scale = \"log\" }}\n\
             {extra}"
        );
        Space::from_toml_str(&text, "new.toml").unwrap()
    }

    fn refused(old: &Space, new: &Space) -> String {
        let (oc, nc) = (old.class(), new.class());
        check(old, &oc, new, &nc, &Pair::BOTH)
            .unwrap_err()
            .to_string()
    }

    #[test]
    fn an_extension_adds_effects_whose_off_value_the_new_space_holds() {
        let old = space("hertz,mindlin", "");
        let new = space(
            "hertz,mindlin,sjkr",
            "ced_pp = { min = 0, max = 3e4 }\nced_pw = { min = 0, max = 3e4, fixed = 0 }\n",
        );
        let ext = check(&old, &old.class(), &new, &new.class(), &Pair::BOTH).unwrap();
        assert_eq!(ext.added, vec!["sjkr"]);
        assert_eq!(
            ext.off_face,
            vec![("ced_pp".to_string(), 0.0), ("ced_pw".to_string(), 0.0)]
        );
        // The reverse drops an effect.
        let e = refused(&new, &old);
        assert!(e.contains("model.class") && e.contains("sjkr"), "{e}");
        // A cohesive wall fixed away from 0: the old runs do not lie there.
        let e = refused(
            &old,
            &space(
                "hertz,mindlin,sjkr",
                "ced_pp = { min = 0, max = 3e4 }\nced_pw = { min = 0, max = 3e4, fixed = 100 }\n",
            ),
        );
        assert!(
            e.contains("parameters.ced_pw") && e.contains("fixed at 100"),
            "{e}"
        );
        // An old parameter whose range moved.
        let moved = Space::from_toml_str(
            "name = \"t\"\n[model]\nclass = \"hertz,mindlin,epsd2\"\n[parameters]\n\
             mu_pp = { min = 0.2, max = 0.8 }\nd50 = { min = 1, max = 20, scale = \"log\" }\n\
             mu_r_pp = { min = 0, max = 0.5 }\nmu_r_pw = { min = 0, max = 0.5, fixed = 0 }\n",
            "new.toml",
        )
        .unwrap();
        let e = refused(&old, &moved);
        assert!(
            e.contains("parameters.mu_pp") && e.contains("may only widen"),
            "{e}"
        );
    }

    #[test]
    fn an_extension_may_widen_ranges_on_the_same_scale() {
        let old = space("hertz,mindlin", "");
        let wide = |mu: &str, d50: &str| {
            Space::from_toml_str(
                &format!(
                    "name = \"t\"\n[model]\nclass = \"hertz,mindlin\"\n[parameters]\n\
                     mu_pp = {{ {mu} }}\nd50 = {{ {d50} }}\n"
                ),
                "new.toml",
            )
            .unwrap()
        };
        let ext = check(
            &old,
            &old.class(),
            &wide(
                "min = 0.2, max = 0.9",
                "min = 0.4, max = 20, scale = \"log\"",
            ),
            &old.class(),
            &Pair::BOTH,
        )
        .unwrap();
        assert!(ext.added.is_empty() && ext.off_face.is_empty());
        assert_eq!(ext.widened, vec![("d50".to_string(), [1.0, 20.0])]);
        assert_eq!(ext.old_runs(), "inside the old ranges d50 [1e0, 2e1]");
        // Refused: the same space, a range moved past an old run, a scale changed.
        let e = refused(&old, &old);
        assert!(e.contains("nothing to extend"), "{e}");
        let e = refused(
            &old,
            &wide("min = 0.3, max = 1.0", "min = 1, max = 20, scale = \"log\""),
        );
        assert!(e.contains("parameters.mu_pp"), "{e}");
        let e = refused(&old, &wide("min = 0.2, max = 0.9", "min = 0.5, max = 20"));
        assert!(e.contains("parameters.d50") && e.contains("Log"), "{e}");
    }
}
