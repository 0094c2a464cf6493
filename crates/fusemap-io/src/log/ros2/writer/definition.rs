//! Message definitions as MCAP `ros2msg` schemas carry them.
//!
//! A reader that has never seen a type (Foxglove, `rosbags`, `ros2 bag` on a machine
//! without the package) rebuilds it from the schema, so the schema holds the whole
//! definition: the top type's `.msg` text, then, for every type it uses directly or
//! indirectly (depth first, in field order, each once), a line of 80 `=`, a line
//! `MSG: pkg/Type` and that type's text. This is the concatenated form rosbag2's
//! `LocalMessageDefinitionSource` writes and the MCAP `ros2msg` profile specifies
//! (<https://mcap.dev/spec/registry#ros2msg>); field lines name nested types without
//! `/msg/` (`std_msgs/Header`), as the `.msg` files do.

/// One `.msg` definition and the message types its fields use.
#[derive(Debug)]
pub struct MsgDef {
    /// `pkg/Type` as field lines and `MSG:` lines spell it (`std_msgs/Header`).
    pub name: &'static str,
    /// The definition: constants, then one `type name` line per field, each ending in `\n`.
    pub text: &'static str,
    /// Types the fields use directly, in field order.
    pub deps: &'static [&'static MsgDef],
}

/// The separator line between definitions.
const SEPARATOR: &str = "================================================================================";

impl MsgDef {
    /// The ROS 2 type name with `/msg/` (`std_msgs/msg/Header`), as topics declare it.
    pub fn ros2_name(&self) -> String {
        match self.name.split_once('/') {
            Some((pkg, ty)) => format!("{pkg}/msg/{ty}"),
            None => self.name.to_string(),
        }
    }

    /// The full concatenated definition (this type, then its dependencies).
    pub fn full_text(&'static self) -> String {
        let mut order: Vec<&'static MsgDef> = Vec::new();
        for dep in self.deps {
            collect(dep, &mut order);
        }
        let mut out = String::from(self.text);
        for def in order {
            if def.name == self.name {
                continue;
            }
            out.push_str(SEPARATOR);
            out.push_str("\nMSG: ");
            out.push_str(def.name);
            out.push('\n');
            out.push_str(def.text);
        }
        out
    }
}

/// Depth-first pre-order, each type once.
fn collect(def: &'static MsgDef, order: &mut Vec<&'static MsgDef>) {
    if order.iter().any(|d| d.name == def.name) {
        return;
    }
    order.push(def);
    for dep in def.deps {
        collect(dep, order);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    static LEAF: MsgDef = MsgDef { name: "a/Leaf", text: "int32 x\n", deps: &[] };
    static MID: MsgDef = MsgDef { name: "a/Mid", text: "a/Leaf l\n", deps: &[&LEAF] };
    static TOP: MsgDef = MsgDef { name: "b/Top", text: "a/Mid m\na/Leaf k\n", deps: &[&MID, &LEAF] };

    #[test]
    fn dependencies_depth_first_each_once() {
        let sep = SEPARATOR;
        assert_eq!(
            TOP.full_text(),
            format!("a/Mid m\na/Leaf k\n{sep}\nMSG: a/Mid\na/Leaf l\n{sep}\nMSG: a/Leaf\nint32 x\n")
        );
        assert_eq!(LEAF.full_text(), "int32 x\n");
        assert_eq!(TOP.ros2_name(), "b/msg/Top");
        assert_eq!(SEPARATOR.len(), 80);
    }
}
