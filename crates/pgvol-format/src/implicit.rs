//! Node graphs of the 3MF Implicit extension: an `<i:implicitfunction>` built node by node, each
//! node's inputs referring to earlier nodes' outputs as `node.output`, written as XML.
//!
//! Only the nodes pgvol emits are here. Node and port names follow the published Volumetric and
//! Implicit 1.0 text (see `docs/interop.md`); identifiers are short (`n12`) because a graph is
//! written once per package and read by programs, and displaynames (optional) are left out.

use std::fmt::Write;

/// The data type of a port: what an input reference or an output element is called.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PortType {
    Scalar,
    Vector,
    ResourceId,
}

impl PortType {
    fn output_element(self) -> &'static str {
        match self {
            PortType::Scalar => "scalar",
            PortType::Vector => "vector",
            PortType::ResourceId => "resourceid",
        }
    }

    fn reference_element(self) -> &'static str {
        match self {
            PortType::Scalar => "scalarref",
            PortType::Vector => "vectorref",
            PortType::ResourceId => "resourceref",
        }
    }
}

/// An output of a node or an input of the function, to be connected to later nodes.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Port {
    reference: String,
    kind: PortType,
}

impl Port {
    pub fn kind(&self) -> PortType {
        self.kind
    }
}

/// Element-wise nodes of one operand (scalar or vector).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Unary {
    Sin,
    Cos,
    Abs,
}

/// Element-wise nodes of two operands of the same type.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Binary {
    Add,
    Sub,
    Mul,
    Div,
    Min,
    Max,
}

struct Node {
    element: &'static str,
    identifier: String,
    attributes: Vec<(&'static str, String)>,
    inputs: Vec<(&'static str, Port)>,
    outputs: Vec<(&'static str, PortType)>,
}

/// An implicit function of one vector input `pos` and one scalar output, built in order (so the
/// graph is acyclic by construction).
pub struct ImplicitFunction {
    nodes: Vec<Node>,
    output: Option<(String, Port)>,
}

impl Default for ImplicitFunction {
    fn default() -> Self {
        Self::new()
    }
}

/// Shortest text that reads back to the same f64.
fn num(v: f64) -> String {
    format!("{v}")
}

impl ImplicitFunction {
    pub fn new() -> ImplicitFunction {
        ImplicitFunction {
            nodes: Vec::new(),
            output: None,
        }
    }

    /// The function's input: the position, in the level set's function coordinates.
    pub fn position(&self) -> Port {
        Port {
            reference: "inputs.pos".into(),
            kind: PortType::Vector,
        }
    }

    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Adds a node; returns its outputs in the order given.
    fn node(
        &mut self,
        element: &'static str,
        attributes: Vec<(&'static str, String)>,
        inputs: Vec<(&'static str, Port)>,
        outputs: &[(&'static str, PortType)],
    ) -> Vec<Port> {
        let identifier = format!("n{}", self.nodes.len());
        let ports = outputs
            .iter()
            .map(|&(name, kind)| Port {
                reference: format!("{identifier}.{name}"),
                kind,
            })
            .collect();
        self.nodes.push(Node {
            element,
            identifier,
            attributes,
            inputs,
            outputs: outputs.to_vec(),
        });
        ports
    }

    fn single(
        &mut self,
        element: &'static str,
        inputs: Vec<(&'static str, Port)>,
        kind: PortType,
    ) -> Port {
        self.node(element, Vec::new(), inputs, &[("result", kind)])
            .remove(0)
    }

    pub fn constant(&mut self, value: f64) -> Port {
        self.node(
            "constant",
            vec![("value", num(value))],
            Vec::new(),
            &[("value", PortType::Scalar)],
        )
        .remove(0)
    }

    pub fn constvec(&mut self, v: [f64; 3]) -> Port {
        self.node(
            "constvec",
            vec![("x", num(v[0])), ("y", num(v[1])), ("z", num(v[2]))],
            Vec::new(),
            &[("vector", PortType::Vector)],
        )
        .remove(0)
    }

    /// The id of a function resource, for [`ImplicitFunction::call`].
    pub fn resource(&mut self, id: u32) -> Port {
        self.node(
            "constresourceid",
            vec![("value", id.to_string())],
            Vec::new(),
            &[("value", PortType::ResourceId)],
        )
        .remove(0)
    }

    pub fn unary(&mut self, op: Unary, a: &Port) -> Port {
        let element = match op {
            Unary::Sin => "sin",
            Unary::Cos => "cos",
            Unary::Abs => "abs",
        };
        self.single(element, vec![("A", a.clone())], a.kind)
    }

    /// `a op b`; both operands of one type (vectors: component-wise).
    pub fn binary(&mut self, op: Binary, a: &Port, b: &Port) -> Port {
        debug_assert_eq!(a.kind, b.kind, "operands of one type");
        let element = match op {
            Binary::Add => "addition",
            Binary::Sub => "subtraction",
            Binary::Mul => "multiplication",
            Binary::Div => "division",
            Binary::Min => "min",
            Binary::Max => "max",
        };
        self.single(element, vec![("A", a.clone()), ("B", b.clone())], a.kind)
    }

    pub fn dot(&mut self, a: &Port, b: &Port) -> Port {
        self.single(
            "dot",
            vec![("A", a.clone()), ("B", b.clone())],
            PortType::Scalar,
        )
    }

    pub fn length(&mut self, a: &Port) -> Port {
        self.single("length", vec![("A", a.clone())], PortType::Scalar)
    }

    /// `max(lo, min(a, hi))`.
    pub fn clamp(&mut self, a: &Port, lo: &Port, hi: &Port) -> Port {
        self.single(
            "clamp",
            vec![("A", a.clone()), ("min", lo.clone()), ("max", hi.clone())],
            a.kind,
        )
    }

    /// `a < b ? c : d`.
    pub fn select(&mut self, a: &Port, b: &Port, c: &Port, d: &Port) -> Port {
        self.single(
            "select",
            vec![
                ("A", a.clone()),
                ("B", b.clone()),
                ("C", c.clone()),
                ("D", d.clone()),
            ],
            c.kind,
        )
    }

    /// The vector `(a, a, a)`.
    pub fn splat(&mut self, a: &Port) -> Port {
        self.single("vectorfromscalar", vec![("A", a.clone())], PortType::Vector)
    }

    pub fn decompose(&mut self, v: &Port) -> [Port; 3] {
        let ports = self.node(
            "decomposevector",
            Vec::new(),
            vec![("A", v.clone())],
            &[
                ("x", PortType::Scalar),
                ("y", PortType::Scalar),
                ("z", PortType::Scalar),
            ],
        );
        [ports[0].clone(), ports[1].clone(), ports[2].clone()]
    }

    pub fn compose(&mut self, [x, y, z]: [&Port; 3]) -> Port {
        self.single(
            "composevector",
            vec![("x", x.clone()), ("y", y.clone()), ("z", z.clone())],
            PortType::Vector,
        )
    }

    /// Output `output` (a scalar) of the function resource `function` at `pos`.
    pub fn call(&mut self, function: &Port, pos: &Port, output: &'static str) -> Port {
        self.node(
            "functioncall",
            Vec::new(),
            vec![("functionID", function.clone()), ("pos", pos.clone())],
            &[(output, PortType::Scalar)],
        )
        .remove(0)
    }

    /// Names the function's scalar output.
    pub fn set_output(&mut self, name: &str, port: &Port) {
        self.output = Some((name.to_string(), port.clone()));
    }

    /// The output's name, once set.
    pub fn output_name(&self) -> Option<&str> {
        self.output.as_ref().map(|(name, _)| name.as_str())
    }

    /// The `<i:implicitfunction>` element with resource `id`, indented by `indent` spaces.
    pub fn xml(&self, id: u32, name: &str, indent: usize) -> String {
        let pad = " ".repeat(indent);
        let mut s = String::new();
        // Writing to a String cannot fail.
        let _ = writeln!(
            s,
            "{pad}<i:implicitfunction id=\"{id}\" displayname=\"{name}\">\n{pad} <i:in><i:vector identifier=\"pos\"/></i:in>"
        );
        for n in &self.nodes {
            let _ = write!(s, "{pad} <i:{} identifier=\"{}\"", n.element, n.identifier);
            for (k, v) in &n.attributes {
                let _ = write!(s, " {k}=\"{v}\"");
            }
            s.push('>');
            if !n.inputs.is_empty() {
                s.push_str("<i:in>");
                for (k, p) in &n.inputs {
                    let _ = write!(
                        s,
                        "<i:{} identifier=\"{k}\" ref=\"{}\"/>",
                        p.kind.reference_element(),
                        p.reference
                    );
                }
                s.push_str("</i:in>");
            }
            s.push_str("<i:out>");
            for (k, kind) in &n.outputs {
                let _ = write!(s, "<i:{} identifier=\"{k}\"/>", kind.output_element());
            }
            let _ = writeln!(s, "</i:out></i:{}>", n.element);
        }
        if let Some((name, port)) = &self.output {
            let _ = writeln!(
                s,
                "{pad} <i:out><i:{} identifier=\"{name}\" ref=\"{}\"/></i:out>",
                port.kind.reference_element(),
                port.reference
            );
        }
        let _ = writeln!(s, "{pad}</i:implicitfunction>");
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nodes_refer_to_earlier_outputs_by_identifier() {
        let mut f = ImplicitFunction::new();
        let pos = f.position();
        let [x, _, _] = f.decompose(&pos);
        let s = f.unary(Unary::Sin, &x);
        let c = f.constant(0.5);
        let m = f.binary(Binary::Max, &s, &c);
        f.set_output("shape", &m);
        let xml = f.xml(7, "test", 0);
        assert!(xml.starts_with("<i:implicitfunction id=\"7\""));
        assert!(xml.contains("<i:decomposevector identifier=\"n0\"><i:in><i:vectorref identifier=\"A\" ref=\"inputs.pos\"/></i:in>"));
        assert!(xml.contains(
            "<i:sin identifier=\"n1\"><i:in><i:scalarref identifier=\"A\" ref=\"n0.x\"/>"
        ));
        assert!(xml.contains(
            "<i:constant identifier=\"n2\" value=\"0.5\"><i:out><i:scalar identifier=\"value\"/>"
        ));
        assert!(xml.contains("<i:scalarref identifier=\"B\" ref=\"n2.value\"/>"));
        assert!(
            xml.contains("<i:out><i:scalarref identifier=\"shape\" ref=\"n3.result\"/></i:out>")
        );
        assert_eq!(f.node_count(), 4);
    }
}
