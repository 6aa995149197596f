//! The `--runner` command template: a shell command with `{test}`, `{dir}` and `{id}` filled in per flight,
//! each value shell-quoted so a path with spaces or quotes stays one word.

/// The placeholders a template may use.
pub const PLACEHOLDERS: [&str; 3] = ["test", "dir", "id"];

/// A checked command template.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Template {
    text: String,
}

/// One piece of a template: literal text or a placeholder's name.
#[derive(Debug, PartialEq)]
enum Piece<'a> {
    Text(&'a str),
    Slot(&'a str),
}

/// Splits `text` into literal text and `{name}` placeholders. A placeholder is braces around an identifier
/// (`[A-Za-z_][A-Za-z0-9_]*`) not preceded by `$`, so the shell's `${VAR}` and braces around anything else
/// (`{ a; b; }`, awk's `{print $1}`) are left to the shell.
fn pieces(text: &str) -> Vec<Piece<'_>> {
    let mut out = Vec::new();
    let (bytes, mut start, mut i) = (text.as_bytes(), 0, 0);
    while i < bytes.len() {
        if bytes[i] == b'{' && (i == 0 || bytes[i - 1] != b'$') {
            let name_len = bytes[i + 1..]
                .iter()
                .take_while(|b| b.is_ascii_alphanumeric() || **b == b'_')
                .count();
            let end = i + 1 + name_len;
            let ident = name_len > 0 && !bytes[i + 1].is_ascii_digit();
            if ident && bytes.get(end) == Some(&b'}') {
                if start < i {
                    out.push(Piece::Text(&text[start..i]));
                }
                out.push(Piece::Slot(&text[i + 1..end]));
                i = end + 1;
                start = i;
                continue;
            }
        }
        i += 1;
    }
    if start < text.len() {
        out.push(Piece::Text(&text[start..]));
    }
    out
}

impl Template {
    /// Checks `text`: not empty, `{test}` present, no unknown `{placeholder}`.
    pub fn parse(text: &str) -> Result<Self, String> {
        Self::parse_for(text, "--runner", "test", "the job would not know which test to fly")
    }

    /// The command that cancels a job the engine still holds (`scancel --name {id}`): as [`Self::parse`], with
    /// `{id}` required instead of `{test}`.
    pub fn parse_cancel(text: &str) -> Result<Self, String> {
        Self::parse_for(text, "--runner-cancel", "id", "it would not know which job to cancel")
    }

    fn parse_for(text: &str, flag: &str, required: &str, why: &str) -> Result<Self, String> {
        if text.trim().is_empty() {
            return Err(format!("{flag}: the command template is empty"));
        }
        let slots: Vec<&str> = pieces(text)
            .into_iter()
            .filter_map(|p| match p {
                Piece::Slot(s) => Some(s),
                Piece::Text(_) => None,
            })
            .collect();
        if let Some(bad) = slots.iter().find(|s| !PLACEHOLDERS.contains(s)) {
            return Err(format!(
                "{flag}: unknown placeholder {{{bad}}} in {text:?}; the placeholders are {{test}}, {{dir}} and \
                 {{id}} (write ${{{bad}}} for a shell variable)"
            ));
        }
        if !slots.contains(&required) {
            return Err(format!(
                "{flag}: the command template {text:?} has no {{{required}}}: {why}"
            ));
        }
        Ok(Self { text: text.to_string() })
    }

    /// The template as given.
    pub fn as_str(&self) -> &str {
        &self.text
    }

    /// The command for one job: each placeholder replaced by its value, shell-quoted.
    pub fn render(&self, test: &str, dir: &str, id: &str) -> String {
        pieces(&self.text)
            .into_iter()
            .map(|p| match p {
                Piece::Text(t) => t.to_string(),
                Piece::Slot("test") => shell_quote(test),
                Piece::Slot("dir") => shell_quote(dir),
                Piece::Slot("id") => shell_quote(id),
                // parse() refused every other name.
                Piece::Slot(other) => format!("{{{other}}}"),
            })
            .collect()
    }
}

/// `s` as one POSIX shell word: bare when it is made of characters the shell never interprets, otherwise in
/// single quotes (each `'` written as `'\''`).
pub fn shell_quote(s: &str) -> String {
    let plain = |c: char| c.is_ascii_alphanumeric() || "-_./:=@%+,".contains(c);
    if !s.is_empty() && s.chars().all(plain) {
        s.to_string()
    } else {
        format!("'{}'", s.replace('\'', r"'\''"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn placeholders_are_filled_and_quoted() {
        let t = Template::parse("aerialist exec --test {test} --path {dir} --id {id}").unwrap();
        assert_eq!(
            t.render("/a b/t.yaml", "/j/c_1", "prg-1"),
            "aerialist exec --test '/a b/t.yaml' --path /j/c_1 --id prg-1"
        );
        assert_eq!(Template::parse("x {test}{test}").unwrap().render("a", "", ""), "x aa");
    }

    #[test]
    fn shell_syntax_in_braces_is_left_alone() {
        let text = "srun -J ${SLURM_JOB_NAME} sh -c '{ run {test}; }' | awk '{print $1}' {} {1x}";
        let t = Template::parse(text).unwrap();
        let out = t.render("t.yaml", "d", "i");
        assert_eq!(
            out,
            "srun -J ${SLURM_JOB_NAME} sh -c '{ run t.yaml; }' | awk '{print $1}' {} {1x}"
        );
    }

    #[test]
    fn bad_templates_are_refused_by_name() {
        let e = Template::parse("aerialist exec --path {dir}").unwrap_err();
        assert!(e.contains("no {test}"), "{e}");
        let e = Template::parse("fly {test} --out {output}").unwrap_err();
        assert!(
            e.contains("unknown placeholder {output}") && e.contains("${output}"),
            "{e}"
        );
        assert!(Template::parse("  ").unwrap_err().contains("empty"));
        let e = Template::parse_cancel("scancel --name {test}").unwrap_err();
        assert!(e.starts_with("--runner-cancel") && e.contains("no {id}"), "{e}");
        let c = Template::parse_cancel("scancel --name {id}").unwrap();
        assert_eq!(c.render("t", "d", "prg-1-2-1"), "scancel --name prg-1-2-1");
    }

    #[test]
    fn quoting_survives_the_shell() {
        for s in [
            "plain",
            "with space",
            "it's",
            "$(rm -rf /)",
            "a\"b\\c",
            "",
            "new\nline",
            "*?[]",
        ] {
            let out = std::process::Command::new("sh")
                .arg("-c")
                .arg(format!("printf %s {}", shell_quote(s)))
                .output()
                .unwrap();
            assert_eq!(String::from_utf8_lossy(&out.stdout), s, "{s:?}");
        }
    }
}
