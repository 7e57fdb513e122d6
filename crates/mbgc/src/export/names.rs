//! Column names made into identifiers of a target language. A column may be called anything
//! (`x-y`, `2nd`, `mu pp`); an export must still compile (Rust) or parse (sympy) and mean the
//! same variables, so names are mapped to valid identifiers and made unique.

/// `sanitize` each name, then suffix `_2`, `_3`, ... until it differs from every earlier result
/// and from `taken`.
pub fn unique(
    names: &[String],
    sanitize: impl Fn(&str) -> String,
    taken: &[String],
) -> Vec<String> {
    let mut out: Vec<String> = Vec::with_capacity(names.len());
    for n in names {
        let base = sanitize(n);
        let mut candidate = base.clone();
        let mut k = 2;
        while out.contains(&candidate) || taken.contains(&candidate) {
            candidate = format!("{base}_{k}");
            k += 1;
        }
        out.push(candidate);
    }
    out
}

/// ASCII letters, digits and `_`, not starting with a digit (Rust and Python identifiers).
pub fn ascii_identifier(name: &str) -> String {
    let mut s: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    if s.is_empty() || s.starts_with(|c: char| c.is_ascii_digit()) {
        s.insert(0, '_');
    }
    // `_` alone (from `μ`, `%`, `-`) is a pattern, not a variable, in Rust.
    if s.chars().all(|c| c == '_') {
        s.push('x');
    }
    s
}

/// Text safe inside a one-line comment: control characters (a newline would end the comment)
/// become spaces.
pub fn comment_text(name: &str) -> String {
    name.chars()
        .map(|c| if c.is_control() { ' ' } else { c })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn awkward_names_become_distinct_identifiers() {
        let names: Vec<String> = ["x-y", "x_y", "x y", "2nd", ""]
            .iter()
            .map(|s| s.to_string())
            .collect();
        let ids = unique(&names, ascii_identifier, &["x_y_2".to_string()]);
        assert_eq!(ids, ["x_y", "x_y_3", "x_y_4", "_2nd", "_x"]);
        assert_eq!(ascii_identifier("μ"), "_x");
        assert_eq!(ascii_identifier("--"), "__x");
        assert_eq!(comment_text("a\nb\r"), "a b ");
    }
}
