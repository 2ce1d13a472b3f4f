//! The JSON examples of protocol/README.md, by fence tag (`json client`,
//! `json server`), shared by the README and schema tests.

/// The bodies of the README's code blocks fenced as ```` ```json <tag> ````.
pub fn readme_blocks(tag: &str) -> Vec<String> {
    let text = include_str!("../../README.md");
    let open = format!("```json {tag}");
    let mut out = Vec::new();
    let mut current: Option<String> = None;
    for line in text.lines() {
        match &mut current {
            None if line.trim() == open => current = Some(String::new()),
            Some(body) if line.trim() == "```" => {
                out.push(std::mem::take(body));
                current = None;
            }
            Some(body) => {
                body.push_str(line);
                body.push('\n');
            }
            None => {}
        }
    }
    out
}
