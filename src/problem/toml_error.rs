//! Messages for TOML syntax and type errors: one line naming the line,
//! column, table and key.

/// One line: what is wrong, where (line:column), and the key when known.
pub(super) fn describe_toml_error(text: &str, e: &toml::de::Error) -> String {
    let msg = e.message().trim().replace('\n', "; ");
    match e.span() {
        Some(span) => {
            let mut start = span.start.min(text.len());
            while !text.is_char_boundary(start) {
                start -= 1;
            }
            let line = text[..start].matches('\n').count() + 1;
            let line_start = text[..start].rfind('\n').map(|i| i + 1).unwrap_or(0);
            let col = start - line_start + 1;
            let line_text = text[line_start..].lines().next().unwrap_or("");
            let snippet: String = text[start..]
                .lines()
                .next()
                .unwrap_or("")
                .chars()
                .take(40)
                .collect();
            // The table the error is in; none when the error is in a table
            // header itself (the header is the snippet).
            let table = if line_text.trim_start().starts_with('[') {
                String::new()
            } else {
                enclosing_table(text, line_start)
            };
            // The key of a `key = value` line, when the error is in its value.
            let key = line_text
                .split_once('=')
                .map(|(k, _)| k.trim())
                .filter(|k| {
                    !k.is_empty()
                        && !k.starts_with('[')
                        && line_start + line_text.find('=').unwrap_or(0) < start
                })
                .map(|k| format!(", key `{k}`"))
                .unwrap_or_default();
            let at = match snippet.trim() {
                "" => String::new(),
                sn => format!(" (at `{sn}`)"),
            };
            format!("line {line}, column {col}{table}{key}: {msg}{at}")
        }
        None => msg,
    }
}

/// " in [table]" for the table header that precedes byte offset `pos`.
fn enclosing_table(text: &str, pos: usize) -> String {
    text[..pos]
        .lines()
        .rev()
        .map(str::trim)
        .find(|l| l.starts_with('['))
        .map(|l| format!(" in {}", l.split('#').next().unwrap_or(l).trim()))
        .unwrap_or_default()
}
