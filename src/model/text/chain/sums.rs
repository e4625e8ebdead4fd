//! L's additive structure: its sums, each with its sign, and the terms outside them (the
//! rest), read from the parse tree; and the expression of a site's term or of the rest's over
//! its slots, joined from their subtrees with each site replaced by its slot.

use std::collections::BTreeMap;

use super::{Rest, SumTerm, TextChainModel};
use crate::model::text::error::TextError;
use crate::model::text::expression::Expression;
use crate::model::text::parse::SumCall;
use crate::model::text::tree::{Binary, Index, Node, Site, Symbol};

impl TextChainModel {
    /// Σ ± body of the sums marked `active`, over the slots of a site's window, a slot at
    /// offset k being zero where `outside(k)`.
    pub(super) fn site_expression(
        &self,
        active: &[bool],
        outside: &dyn Fn(i64) -> bool,
        parameter_count: usize,
    ) -> Result<Expression, TextError> {
        let families = self.families.len() as i64;
        let a = self.window.0;
        let terms: Vec<(bool, usize)> = self
            .sums
            .iter()
            .zip(active)
            .filter(|(_, active)| **active)
            .map(|(sum, _)| (sum.negative, sum.body))
            .collect();
        let slot = |site: Site| {
            let k = site.index.offset;
            if outside(k) {
                return Node::Number(0.0);
            }
            // k ≥ a and the family is below the count: a slot below the width.
            let slot = ((k - a) * families) as usize + site.family;
            Node::Symbol(if site.velocity {
                Symbol::Velocity(slot)
            } else {
                Symbol::Coordinate(slot)
            })
        };
        let (nodes, root) = join(&self.tree, &terms, &slot);
        Expression::from_tree(nodes, root, "lagrangian", parameter_count)
    }

    /// The rest of L over its slots, a site's slot being zero where `site_of` gives none.
    pub(super) fn rest_expression(
        &self,
        site_of: &dyn Fn(Index) -> Option<i64>,
        parameter_count: usize,
    ) -> Result<Expression, TextError> {
        let slot = |site: Site| {
            if site_of(site.index).is_none() {
                return Node::Number(0.0);
            }
            let slot = self
                .rest_sites
                .iter()
                .position(|known| *known == (site.family, site.index))
                .unwrap_or(0);
            Node::Symbol(if site.velocity {
                Symbol::Velocity(slot)
            } else {
                Symbol::Coordinate(slot)
            })
        };
        let (nodes, root) = join(&self.tree, &self.rest, &slot);
        Expression::from_tree(nodes, root, "lagrangian", parameter_count)
    }
}

/// L's terms: the sums, each with its sign, and the terms outside them, (negative, node),
/// from the additive structure at `root`; an error for a sum elsewhere.
pub(super) fn terms(
    nodes: &[Node],
    root: usize,
    calls: &[SumCall],
) -> Result<(Vec<SumTerm>, Rest), TextError> {
    let mut sums: Vec<Option<SumTerm>> = vec![None; calls.len()];
    let mut rest = Vec::new();
    let mut stack = vec![(false, root)];
    while let Some((negative, node)) = stack.pop() {
        match nodes[node] {
            Node::Binary(Binary::Add, x, y) => {
                stack.extend([(negative, y), (negative, x)]);
            }
            Node::Binary(Binary::Subtract, x, y) => {
                stack.extend([(!negative, y), (negative, x)]);
            }
            Node::Negate(x) => stack.push((!negative, x)),
            _ => match calls.iter().position(|call| call.placeholder == node) {
                Some(i) => {
                    let call = calls[i];
                    sums[i] = Some(SumTerm {
                        negative,
                        lower: call.lower,
                        upper: call.upper,
                        body: call.body,
                        column: call.column,
                        velocities: velocities(nodes, call.body),
                    });
                }
                None => rest.push((negative, node)),
            },
        }
    }
    calls
        .iter()
        .zip(sums)
        .map(|(call, sum)| {
            sum.ok_or_else(|| TextError::Indexing {
                field: "lagrangian".into(),
                column: call.column,
                symbol: "sum".into(),
                message: "a sum is a term of L, added or subtracted (sum(...) - sum(...)), not \
                          inside a product, a power or a function"
                    .into(),
            })
        })
        .collect::<Result<Vec<_>, _>>()
        .map(|sums| (sums, rest))
}

/// Which nodes the subtree at `root` holds (each node after its children in the arena).
fn subtree(nodes: &[Node], root: usize) -> Vec<bool> {
    let mut reached = vec![false; root + 1];
    reached[root] = true;
    for node in (0..=root).rev() {
        if !reached[node] {
            continue;
        }
        match nodes[node] {
            Node::Negate(x) | Node::PowerInteger(x, _) | Node::Call(_, x) => reached[x] = true,
            Node::Binary(_, x, y) => {
                reached[x] = true;
                reached[y] = true;
            }
            Node::Number(_) | Node::Symbol(_) => {}
        }
    }
    reached
}

/// The (family, offset) of the velocities the sum body at `body` reads, each once.
fn velocities(nodes: &[Node], body: usize) -> Vec<(usize, i64)> {
    let mut found = Vec::new();
    for (node, reached) in nodes.iter().zip(subtree(nodes, body)) {
        if let (Node::Symbol(Symbol::Site(site)), true) = (node, reached)
            && site.velocity
            && !found.contains(&(site.family, site.index.offset))
        {
            found.push((site.family, site.index.offset));
        }
    }
    found
}

/// A new arena holding Σ ± subtree over `terms` (negative, root) of `nodes`, each site
/// replaced by `slot(site)`, and its root (the number 0 for no term).
fn join(
    nodes: &[Node],
    terms: &[(bool, usize)],
    slot: &dyn Fn(Site) -> Node,
) -> (Vec<Node>, usize) {
    let mut out: Vec<Node> = Vec::new();
    let mut total: Option<usize> = None;
    for &(negative, root) in terms {
        let reached = subtree(nodes, root);
        let mut map: BTreeMap<usize, usize> = BTreeMap::new();
        for (node, _) in reached.iter().enumerate().filter(|(_, reached)| **reached) {
            let copied = match nodes[node] {
                Node::Symbol(Symbol::Site(site)) => slot(site),
                Node::Negate(x) => Node::Negate(map[&x]),
                Node::PowerInteger(x, power) => Node::PowerInteger(map[&x], power),
                Node::Call(function, x) => Node::Call(function, map[&x]),
                Node::Binary(binary, x, y) => Node::Binary(binary, map[&x], map[&y]),
                other => other,
            };
            out.push(copied);
            map.insert(node, out.len() - 1);
        }
        let term = out.len() - 1;
        total = Some(match (total, negative) {
            (None, false) => term,
            (None, true) => {
                out.push(Node::Negate(term));
                out.len() - 1
            }
            (Some(sum), negative) => {
                let binary = if negative {
                    Binary::Subtract
                } else {
                    Binary::Add
                };
                out.push(Node::Binary(binary, sum, term));
                out.len() - 1
            }
        });
    }
    match total {
        Some(root) => (out, root),
        None => (vec![Node::Number(0.0)], 0),
    }
}
