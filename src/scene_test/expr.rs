//! The expressions of scene tests: programs in the Common Expression Language over the
//! scene's state at one step (see [`super::state`]), with the paths each one reads found
//! from its syntax tree, so that a name the scene does not have is refused before the scene
//! runs, and a failure can show what every path held.
//!
//! Besides CEL's standard library and its `math`, `strings` and `lists` extensions
//! (`math.abs`, `math.greatest`, `lowerAscii()`, `sort()`, ...), expressions may call:
//!
//! | function | true or value |
//! |---|---|
//! | `approx(a, b, tolerance)` | numbers, or lists of numbers element by element, within `tolerance` |
//! | `distance(p, q)` | the Euclidean distance between two points (lists of numbers) |

use cel::common::ast::{EntryExpr, Expr, IdedExpr};
use cel::extractors::Arguments;
use cel::objects::{Key, Map as CelMap};
use cel::{Context, Env, ExecutionError, Program, Value};
use serde_json::{Map, Value as Json};
use std::collections::HashMap;
use std::fmt::Write as _;
use std::sync::{Arc, LazyLock};

/// Longest expression accepted, in bytes.
pub const MAX_EXPRESSION_LEN: usize = 4096;

/// CEL's standard environment with its `math`, `strings` and `lists` extensions, shared by
/// every expression.
static ENV: LazyLock<Arc<Env>> = LazyLock::new(|| {
    let mut env = Env::stdlib();
    for extension in [cel::extensions::math, cel::extensions::strings, cel::extensions::lists] {
        env.add_extension(extension).expect("CEL's extensions declare names the standard library does not");
    }
    Arc::new(env)
});

/// The namespaces of the extensions' functions (`math.abs`, `lists.range`, ...): these names
/// are not variables.
pub const NAMESPACES: &[&str] = &["math", "lists", "strings"];

/// A problem with an expression, at a 1-based line and column inside it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ExprError {
    /// 1-based line within the expression.
    pub line: usize,
    /// 1-based column within that line.
    pub column: usize,
    /// What is wrong, with what exists nearby.
    pub message: String,
}

/// A path an expression reads: a variable and the fields selected from it.
#[derive(Debug)]
struct Read {
    /// `sloth`, `distance_travelled`, ...
    segments: Vec<String>,
    /// Byte offset in the expression where each segment starts.
    offsets: Vec<usize>,
    /// The path alone, compiled, to show its value when the expression fails.
    program: Program,
}

impl Read {
    fn text(&self) -> String {
        self.segments.join(".")
    }
}

/// One compiled expression.
#[derive(Debug)]
pub struct Check {
    source: String,
    program: Program,
    reads: Vec<Read>,
}

/// What an expression said at one step.
#[derive(Debug, Clone, PartialEq)]
pub enum Verdict {
    /// It held.
    True,
    /// It did not hold.
    False,
    /// It could not be evaluated (a type mismatch, a key missing at this step, ...), or gave
    /// something else than true or false.
    Error(String),
}

impl Check {
    /// Parses an expression and finds the paths it reads.
    pub fn compile(source: &str) -> Result<Self, ExprError> {
        if source.len() > MAX_EXPRESSION_LEN {
            return Err(ExprError {
                line: 1,
                column: 1,
                message: format!("the expression is {} bytes long, more than {MAX_EXPRESSION_LEN}", source.len()),
            });
        }
        let program = ENV.compile(source).map_err(|errors| {
            let first = errors.errors.first();
            let (line, column) = first.map_or((1, 1), |e| (e.pos.0.max(1) as usize, e.pos.1.max(0) as usize + 1));
            let message = first.map_or_else(|| "the expression does not parse".to_string(), |e| e.msg.clone());
            ExprError { line, column, message: format!("the expression does not parse: {message}") }
        })?;
        let mut chains = Vec::new();
        collect_reads(program.expression(), &mut Vec::new(), &mut chains);
        let mut reads: Vec<Read> = Vec::new();
        for chain in chains {
            let offsets = chain
                .iter()
                .enumerate()
                .map(|(i, (_, id))| {
                    // An identifier's node starts at its name; a selection's at its dot.
                    let start = program.source_info().offset_for(*id).map_or(0, |(start, _)| start as usize);
                    if i == 0 { start } else { start + 1 }
                })
                .collect();
            let segments: Vec<String> = chain.into_iter().map(|(name, _)| name).collect();
            if reads.iter().any(|read| read.segments == segments) {
                continue;
            }
            let program = ENV.compile(&segments.join(".")).map_err(|_| ExprError {
                line: 1,
                column: 1,
                message: format!("`{}` cannot be read on its own", segments.join(".")),
            })?;
            reads.push(Read { segments, offsets, program });
        }
        Ok(Self { source: source.to_string(), program, reads })
    }

    /// The expression as written.
    pub fn source(&self) -> &str {
        &self.source
    }

    /// The paths the expression reads, each a variable and the fields selected from it.
    pub fn paths(&self) -> impl Iterator<Item = &[String]> {
        self.reads.iter().map(|read| read.segments.as_slice())
    }

    /// Checks every path the expression reads against the scene's state, field by field as far
    /// as the state has objects: a variable or field it lacks is an error naming the nearest.
    pub fn check_names(&self, scope: &Map<String, Json>) -> Result<(), ExprError> {
        for read in &self.reads {
            let mut fields = scope;
            for (depth, segment) in read.segments.iter().enumerate() {
                match fields.get(segment) {
                    Some(Json::Object(inner)) => fields = inner,
                    Some(_) => break,
                    None => {
                        let (line, column) = self.position(read.offsets[depth]);
                        let owner = if depth == 0 {
                            "the scene has no entity or variable".to_string()
                        } else {
                            format!("`{}` has no field", read.segments[..depth].join("."))
                        };
                        let message = format!("{owner} `{segment}`{}", nearby(segment, fields.keys()));
                        return Err(ExprError { line, column, message });
                    }
                }
            }
        }
        Ok(())
    }

    /// Evaluates the expression in `context` (see [`context`]).
    pub fn evaluate(&self, context: &Context) -> Verdict {
        match self.program.execute(context) {
            Ok(Value::Bool(true)) => Verdict::True,
            Ok(Value::Bool(false)) => Verdict::False,
            Ok(other) => Verdict::Error(format!("gives {}, not true or false", describe(&other))),
            Err(error) => Verdict::Error(error.to_string()),
        }
    }

    /// Every path the expression reads with its value in `context`:
    /// `sloth.distance_travelled = 0.62, sloth.support = "tree/bough"`.
    pub fn values_read(&self, context: &Context) -> String {
        let mut out = String::new();
        for read in &self.reads {
            if !out.is_empty() {
                out.push_str(", ");
            }
            let value = match read.program.execute(context) {
                Ok(value) => describe(&value),
                Err(error) => format!("<{error}>"),
            };
            let _ = write!(out, "{} = {value}", read.text());
        }
        out
    }

    /// The 1-based line and column of a byte offset in the expression.
    fn position(&self, offset: usize) -> (usize, usize) {
        let before = &self.source[..offset.min(self.source.len())];
        let line = before.matches('\n').count() + 1;
        let column = before.rfind('\n').map_or(before.chars().count(), |nl| before[nl + 1..].chars().count()) + 1;
        (line, column)
    }
}

/// The qualified names an expression reads (`sloth.feet.front_left`), each segment with its
/// node's id, leaving out the variables its macros bind.
fn collect_reads(expr: &IdedExpr, bound: &mut Vec<String>, out: &mut Vec<Vec<(String, u64)>>) {
    match &expr.expr {
        Expr::Ident(name) => {
            if !bound.contains(name) {
                out.push(vec![(name.clone(), expr.id)]);
            }
        }
        Expr::Select(select) => {
            let mut chain = vec![(select.field.clone(), expr.id)];
            let mut operand = &select.operand;
            loop {
                match &operand.expr {
                    Expr::Select(inner) if !inner.test => {
                        chain.push((inner.field.clone(), operand.id));
                        operand = &inner.operand;
                    }
                    Expr::Ident(name) => {
                        if !bound.contains(name) {
                            chain.push((name.clone(), operand.id));
                            chain.reverse();
                            // `has(a.b)` asks whether `b` exists: only `a` must.
                            if select.test {
                                chain.pop();
                            }
                            out.push(chain);
                        }
                        return;
                    }
                    _ => return collect_reads(operand, bound, out),
                }
            }
        }
        Expr::Call(call) => {
            // `math.abs(x)` names a function, not a variable `math`.
            let namespace = matches!(&call.target, Some(t) if matches!(&t.expr, Expr::Ident(n) if NAMESPACES.contains(&n.as_str())));
            if let Some(target) = call.target.as_ref().filter(|_| !namespace) {
                collect_reads(target, bound, out);
            }
            call.args.iter().for_each(|arg| collect_reads(arg, bound, out));
        }
        Expr::Comprehension(comprehension) => {
            collect_reads(&comprehension.iter_range, bound, out);
            let names =
                [Some(&comprehension.iter_var), comprehension.iter_var2.as_ref(), Some(&comprehension.accu_var)];
            let added = names.iter().flatten().count();
            bound.extend(names.into_iter().flatten().cloned());
            for part in
                [&comprehension.accu_init, &comprehension.loop_cond, &comprehension.loop_step, &comprehension.result]
            {
                collect_reads(part, bound, out);
            }
            bound.truncate(bound.len() - added);
        }
        Expr::List(list) => list.elements.iter().for_each(|element| collect_reads(element, bound, out)),
        Expr::Map(map) => map.entries.iter().for_each(|entry| collect_entry(&entry.expr, bound, out)),
        Expr::Struct(fields) => fields.entries.iter().for_each(|entry| collect_entry(&entry.expr, bound, out)),
        Expr::Literal(_) | Expr::Unspecified => {}
    }
}

fn collect_entry(entry: &EntryExpr, bound: &mut Vec<String>, out: &mut Vec<Vec<(String, u64)>>) {
    match entry {
        EntryExpr::StructField(field) => collect_reads(&field.value, bound, out),
        EntryExpr::MapEntry(entry) => {
            collect_reads(&entry.key, bound, out);
            collect_reads(&entry.value, bound, out);
        }
    }
}

/// `; did you mean `x`? (there are: a, b, c)`: the names closest to `wanted`, then all of them.
pub fn nearby<'a>(wanted: &str, names: impl Iterator<Item = &'a String>) -> String {
    let mut names: Vec<&String> = names.collect();
    if names.is_empty() {
        return String::new();
    }
    names.sort();
    let closest = names
        .iter()
        .map(|name| (strsim::jaro_winkler(wanted, name), *name))
        .filter(|(score, _)| *score > 0.8)
        .max_by(|a, b| a.0.total_cmp(&b.0));
    let suggestion = closest.map(|(_, name)| format!("; did you mean `{name}`?")).unwrap_or_default();
    let listed: Vec<&str> = names.iter().take(40).map(|name| name.as_str()).collect();
    let more = if names.len() > listed.len() { ", ..." } else { "" };
    format!("{suggestion} (there are: {}{more})", listed.join(", "))
}

/// A root context: CEL's environment and Canopy's functions. Each step's variables go into
/// an inner scope of it (see [`super::state::Scope::bind`]).
pub fn context() -> Context<'static, 'static> {
    let mut context = Context::with_env(ENV.clone());
    context.add_function("approx", approx).expect("`approx` is not a standard name");
    context.add_function("distance", distance).expect("`distance` is not a standard name");
    context
}

fn approx(Arguments(args): Arguments) -> Result<Value, ExecutionError> {
    let [a, b, tolerance] = args.as_slice() else { return Err(ExecutionError::invalid_argument_count(3, args.len())) };
    let tolerance =
        number(tolerance).ok_or_else(|| ExecutionError::function_error("approx", "the tolerance is not a number"))?;
    let within = match (a, b) {
        (Value::List(a), Value::List(b)) => {
            let (a, b) = (numbers("approx", a)?, numbers("approx", b)?);
            a.len() == b.len() && a.iter().zip(&b).all(|(a, b)| (a - b).abs() <= tolerance)
        }
        _ => match (number(a), number(b)) {
            (Some(a), Some(b)) => (a - b).abs() <= tolerance,
            _ => return Err(ExecutionError::function_error("approx", "expects two numbers or two lists of numbers")),
        },
    };
    Ok(Value::Bool(within))
}

fn distance(Arguments(args): Arguments) -> Result<Value, ExecutionError> {
    let [Value::List(p), Value::List(q)] = args.as_slice() else {
        return Err(ExecutionError::function_error("distance", "expects two points, lists of numbers"));
    };
    let (p, q) = (numbers("distance", p)?, numbers("distance", q)?);
    if p.len() != q.len() {
        return Err(ExecutionError::function_error(
            "distance",
            format!("the points have {} and {} coordinates", p.len(), q.len()),
        ));
    }
    Ok(Value::Float(p.iter().zip(&q).map(|(a, b)| (a - b) * (a - b)).sum::<f64>().sqrt()))
}

fn number(value: &Value) -> Option<f64> {
    match value {
        Value::Int(v) => Some(*v as f64),
        Value::UInt(v) => Some(*v as f64),
        Value::Float(v) => Some(*v),
        _ => None,
    }
}

fn numbers(function: &str, list: &[Value]) -> Result<Vec<f64>, ExecutionError> {
    list.iter()
        .map(|value| {
            number(value)
                .ok_or_else(|| ExecutionError::function_error(function, "a list holds something else than numbers"))
        })
        .collect()
}

/// A state value as CEL sees it: integers as `int`, other numbers as `double`, objects as
/// maps with string keys.
pub fn to_cel(value: &Json) -> Value {
    match value {
        Json::Null => Value::Null,
        Json::Bool(b) => Value::Bool(*b),
        Json::Number(n) => n.as_i64().map_or_else(|| Value::Float(n.as_f64().unwrap_or(f64::NAN)), Value::Int),
        Json::String(s) => Value::String(Arc::new(s.clone())),
        Json::Array(items) => Value::List(Arc::new(items.iter().map(to_cel).collect())),
        Json::Object(fields) => {
            let map: HashMap<Key, Value> =
                fields.iter().map(|(k, v)| (Key::String(Arc::new(k.clone())), to_cel(v))).collect();
            Value::Map(CelMap { map: Arc::new(map) })
        }
    }
}

/// A value for a message: numbers to six significant digits, strings quoted, lists and maps
/// shortened past 120 characters.
pub fn describe(value: &Value) -> String {
    let mut out = String::new();
    write_value(&mut out, value);
    if out.len() > 120 {
        let cut = (0..=117).rev().find(|&i| out.is_char_boundary(i)).unwrap_or(0);
        out.truncate(cut);
        out.push_str("...");
    }
    out
}

fn write_value(out: &mut String, value: &Value) {
    match value {
        Value::Float(v) => out.push_str(&number_text(*v)),
        Value::Int(v) => {
            let _ = write!(out, "{v}");
        }
        Value::UInt(v) => {
            let _ = write!(out, "{v}u");
        }
        Value::String(s) => {
            let _ = write!(out, "{s:?}");
        }
        Value::Bool(b) => {
            let _ = write!(out, "{b}");
        }
        Value::Null => out.push_str("null"),
        Value::List(items) => {
            out.push('[');
            for (i, item) in items.iter().enumerate() {
                if i > 0 {
                    out.push_str(", ");
                }
                write_value(out, item);
            }
            out.push(']');
        }
        Value::Map(map) => {
            let mut entries: Vec<(String, &Value)> = map
                .map
                .iter()
                .map(|(k, v)| (if let Key::String(s) = k { s.to_string() } else { format!("{k:?}") }, v))
                .collect();
            entries.sort_by(|a, b| a.0.cmp(&b.0));
            out.push('{');
            for (i, (key, item)) in entries.into_iter().enumerate() {
                if i > 0 {
                    out.push_str(", ");
                }
                let _ = write!(out, "{key}: ");
                write_value(out, item);
            }
            out.push('}');
        }
        other => {
            let _ = write!(out, "{other:?}");
        }
    }
}

/// A number to six significant digits, without trailing zeros.
pub fn number_text(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let magnitude = v.abs().log10().floor() as i32;
    if !(-5..15).contains(&magnitude) {
        return format!("{v:.5e}");
    }
    let decimals = (5 - magnitude).max(0) as usize;
    let text = format!("{v:.decimals$}");
    if text.contains('.') { text.trim_end_matches('0').trim_end_matches('.').to_string() } else { text }
}

#[cfg(test)]
mod tests;
