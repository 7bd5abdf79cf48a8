//! Just enough SPIR-V reflection for push-descriptor layouts and layout tests:
//! descriptor bindings (set 0), the push-constant block's size, workgroup size, and the member
//! offsets of named structs. Opcodes and enums from the SPIR-V 1.6 specification.

use crate::error::{Error, Result};
use ash::vk;
use std::collections::HashMap;

const MAGIC: u32 = 0x0723_0203;
const OP_NAME: u32 = 5;
const OP_MEMBER_NAME: u32 = 6;
const OP_EXECUTION_MODE: u32 = 16;
const OP_TYPE_BOOL: u32 = 20;
const OP_TYPE_INT: u32 = 21;
const OP_TYPE_FLOAT: u32 = 22;
const OP_TYPE_VECTOR: u32 = 23;
const OP_TYPE_MATRIX: u32 = 24;
const OP_TYPE_IMAGE: u32 = 25;
const OP_TYPE_SAMPLER: u32 = 26;
const OP_TYPE_SAMPLED_IMAGE: u32 = 27;
/// OpTypeImage's Dim operand for texel buffers.
const DIM_BUFFER: u32 = 5;
const OP_TYPE_ARRAY: u32 = 28;
const OP_TYPE_RUNTIME_ARRAY: u32 = 29;
const OP_TYPE_STRUCT: u32 = 30;
const OP_TYPE_POINTER: u32 = 32;
const OP_TYPE_ACCELERATION_STRUCTURE: u32 = 5341;
const OP_VARIABLE: u32 = 59;
const OP_DECORATE: u32 = 71;
const OP_MEMBER_DECORATE: u32 = 72;
const DEC_BLOCK: u32 = 2;
const DEC_BUFFER_BLOCK: u32 = 3;
const DEC_ARRAY_STRIDE: u32 = 6;
const DEC_BINDING: u32 = 33;
const DEC_SET: u32 = 34;
const DEC_OFFSET: u32 = 35;
const MODE_LOCAL_SIZE: u32 = 17;
const SC_UNIFORM_CONSTANT: u32 = 0;
const SC_UNIFORM: u32 = 2;
const SC_PUSH_CONSTANT: u32 = 9;
const SC_STORAGE_BUFFER: u32 = 12;

/// What a module declares.
#[derive(Debug, Default, Clone)]
pub struct Reflection {
    /// Every descriptor of set 0 the module uses, sorted by slot.
    pub bindings: Vec<Binding>,
    /// Bytes of the push-constant block (0: the module uses none): the end of its last
    /// member.
    pub push_size: u32,
    /// `local_size` of a compute module.
    pub local_size: Option<[u32; 3]>,
    /// Named structs: name → [(member name, byte offset)], in declaration order.
    pub structs: HashMap<String, Vec<(String, u32)>>,
    /// Struct name → array stride of any (runtime) array whose element is that struct.
    pub array_strides: HashMap<String, u32>,
}

/// One descriptor a module declares: its slot, its kind and its name (the variable's,
/// or for an anonymous block its block's, in snake_case: `buffer TileCosts { .. };` is
/// `tile_costs`). Resources are bound by this name (`vk::Bind`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Binding {
    pub slot: u32,
    pub kind: vk::DescriptorType,
    pub name: String,
}

/// `CamelCase` as `snake_case` (a block's type name as a binding name).
pub fn snake_case(name: &str) -> String {
    let mut out = String::with_capacity(name.len() + 4);
    for (i, c) in name.chars().enumerate() {
        if c.is_ascii_uppercase() {
            if i > 0 {
                out.push('_');
            }
            out.push(c.to_ascii_lowercase());
        } else {
            out.push(c);
        }
    }
    out
}

/// Words of a SPIR-V module given as bytes (as `include_bytes!` yields them).
pub fn words(name: &'static str, bytes: &[u8]) -> Result<Vec<u32>> {
    if !bytes.len().is_multiple_of(4) || bytes.len() < 20 {
        return Err(Error::Spirv(
            name,
            format!("{} bytes is not a SPIR-V module", bytes.len()),
        ));
    }
    let words: Vec<u32> = bytes
        .chunks_exact(4)
        .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    if words[0] != MAGIC {
        return Err(Error::Spirv(name, format!("bad magic {:#x}", words[0])));
    }
    Ok(words)
}

fn string(words: &[u32]) -> String {
    let bytes: Vec<u8> = words
        .iter()
        .flat_map(|w| w.to_le_bytes())
        .take_while(|&b| b != 0)
        .collect();
    String::from_utf8_lossy(&bytes).into_owned()
}

/// The instructions of a module that reflection reads, by id.
#[derive(Default)]
struct Module {
    names: HashMap<u32, String>,
    member_names: HashMap<(u32, u32), String>,
    /// (id, decoration) → its first literal.
    decorations: HashMap<(u32, u32), u32>,
    member_offsets: HashMap<(u32, u32), u32>,
    /// id → (opcode, operands after the result).
    types: HashMap<u32, (u32, Vec<u32>)>,
    /// (id, pointer type, storage class).
    variables: Vec<(u32, u32, u32)>,
    local_size: Option<[u32; 3]>,
}

impl Module {
    /// Reads the words of module `name` into the tables (a truncated instruction is an
    /// error).
    fn parse(name: &'static str, words: &[u32]) -> Result<Module> {
        let mut m = Module::default();
        let Module {
            names,
            member_names,
            decorations,
            member_offsets,
            types,
            variables,
            local_size,
        } = &mut m;
        let mut i = 5;
        while i < words.len() {
            let count = (words[i] >> 16) as usize;
            let op = words[i] & 0xffff;
            if count == 0 || i + count > words.len() {
                return Err(Error::Spirv(name, format!("truncated instruction at word {i}")));
            }
            let args = &words[i + 1..i + count];
            match op {
                OP_NAME if !args.is_empty() => {
                    names.insert(args[0], string(&args[1..]));
                }
                OP_MEMBER_NAME if args.len() >= 2 => {
                    member_names.insert((args[0], args[1]), string(&args[2..]));
                }
                OP_EXECUTION_MODE if args.len() >= 5 && args[1] == MODE_LOCAL_SIZE => {
                    *local_size = Some([args[2], args[3], args[4]]);
                }
                OP_DECORATE if args.len() >= 2 => {
                    decorations.insert((args[0], args[1]), args.get(2).copied().unwrap_or(0));
                }
                OP_MEMBER_DECORATE if args.len() >= 4 && args[2] == DEC_OFFSET => {
                    member_offsets.insert((args[0], args[1]), args[3]);
                }
                OP_TYPE_BOOL
                | OP_TYPE_INT
                | OP_TYPE_FLOAT
                | OP_TYPE_VECTOR
                | OP_TYPE_MATRIX
                | OP_TYPE_IMAGE
                | OP_TYPE_SAMPLER
                | OP_TYPE_SAMPLED_IMAGE
                | OP_TYPE_ARRAY
                | OP_TYPE_RUNTIME_ARRAY
                | OP_TYPE_STRUCT
                | OP_TYPE_POINTER
                | OP_TYPE_ACCELERATION_STRUCTURE
                    if !args.is_empty() =>
                {
                    types.insert(args[0], (op, args[1..].to_vec()));
                }
                OP_VARIABLE if args.len() >= 3 => variables.push((args[1], args[0], args[2])),
                _ => {}
            }
            i += count;
        }
        Ok(m)
    }

    /// `t` with its arrays stripped to the element type.
    fn element(&self, mut t: u32) -> u32 {
        while let Some((OP_TYPE_ARRAY | OP_TYPE_RUNTIME_ARRAY, ops)) = self.types.get(&t) {
            t = ops[0];
        }
        t
    }

    /// Bytes of the push-constant block that `ptr` points to (its last member's end).
    fn push_size(&self, name: &'static str, ptr: u32) -> Result<u32> {
        let block = match self.types.get(&ptr) {
            Some((OP_TYPE_POINTER, ops)) if ops.len() >= 2 => ops[1],
            _ => return Err(Error::Spirv(name, "push constants are not a pointer".into())),
        };
        let Some((OP_TYPE_STRUCT, members)) = self.types.get(&block) else {
            return Err(Error::Spirv(name, "push constants are not a block".into()));
        };
        let mut size = 0;
        for (m, &ty) in members.iter().enumerate() {
            let offset = self.member_offsets.get(&(block, m as u32)).copied().unwrap_or(0);
            let member = scalar_size(&self.types, ty)
                .ok_or_else(|| Error::Spirv(name, format!("push constant member {m} has an unsupported type")))?;
            size = size.max(offset + member);
        }
        Ok(size)
    }

    /// The name resources are bound by of variable `id` (a pointer `ptr`) at `binding`:
    /// its own, or its anonymous block's in snake_case.
    fn binding_name(&self, name: &'static str, (id, ptr): (u32, u32), binding: u32) -> Result<String> {
        if let Some(n) = self.names.get(&id).filter(|n| !n.is_empty()) {
            return Ok(n.clone());
        }
        let block = match self.types.get(&ptr) {
            Some((OP_TYPE_POINTER, ops)) if ops.len() >= 2 => self.element(ops[1]),
            _ => return Err(Error::Spirv(name, format!("variable {id} is not a pointer"))),
        };
        match self.names.get(&block).filter(|n| !n.is_empty()) {
            Some(n) => Ok(snake_case(n)),
            None => Err(Error::Spirv(
                name,
                format!("binding {binding} has no name to bind it by"),
            )),
        }
    }

    /// The descriptor type of variable `id` (a pointer `ptr` of storage class `class`)
    /// at `binding`.
    fn descriptor_type(
        &self,
        name: &'static str,
        (id, ptr, class): (u32, u32, u32),
        binding: u32,
    ) -> Result<vk::DescriptorType> {
        let decorations = &self.decorations;
        let pointee = match self.types.get(&ptr) {
            Some((OP_TYPE_POINTER, ops)) if ops.len() >= 2 => self.element(ops[1]),
            _ => return Err(Error::Spirv(name, format!("variable {id} is not a pointer"))),
        };
        Ok(match (class, self.types.get(&pointee)) {
            (SC_STORAGE_BUFFER, _) => vk::DescriptorType::STORAGE_BUFFER,
            (SC_UNIFORM, _) if decorations.contains_key(&(pointee, DEC_BUFFER_BLOCK)) => {
                vk::DescriptorType::STORAGE_BUFFER
            }
            (SC_UNIFORM, _) if decorations.contains_key(&(pointee, DEC_BLOCK)) => vk::DescriptorType::UNIFORM_BUFFER,
            (SC_UNIFORM_CONSTANT, Some((OP_TYPE_SAMPLED_IMAGE, _))) => vk::DescriptorType::COMBINED_IMAGE_SAMPLER,
            (SC_UNIFORM_CONSTANT, Some((OP_TYPE_SAMPLER, _))) => vk::DescriptorType::SAMPLER,
            (SC_UNIFORM_CONSTANT, Some((OP_TYPE_ACCELERATION_STRUCTURE, _))) => {
                vk::DescriptorType::ACCELERATION_STRUCTURE_KHR
            }
            // OpTypeImage operands after the result: sampled type, dim, depth, arrayed, ms, sampled.
            // A texel buffer is an image of dim Buffer (`utextureBuffer`, `imageBuffer`).
            (SC_UNIFORM_CONSTANT, Some((OP_TYPE_IMAGE, ops))) if ops.len() >= 6 && ops[1] == DIM_BUFFER => {
                if ops[5] == 2 {
                    vk::DescriptorType::STORAGE_TEXEL_BUFFER
                } else {
                    vk::DescriptorType::UNIFORM_TEXEL_BUFFER
                }
            }
            (SC_UNIFORM_CONSTANT, Some((OP_TYPE_IMAGE, ops))) if ops.len() >= 6 && ops[5] == 2 => {
                vk::DescriptorType::STORAGE_IMAGE
            }
            (SC_UNIFORM_CONSTANT, Some((OP_TYPE_IMAGE, _))) => vk::DescriptorType::SAMPLED_IMAGE,
            _ => {
                return Err(Error::Spirv(
                    name,
                    format!("binding {binding}: unsupported descriptor kind"),
                ))
            }
        })
    }
}

/// Reflects a module.
pub fn reflect(name: &'static str, words: &[u32]) -> Result<Reflection> {
    let module = Module::parse(name, words)?;
    let mut out = Reflection {
        local_size: module.local_size,
        ..Reflection::default()
    };
    for &(id, ptr, class) in &module.variables {
        if class == SC_PUSH_CONSTANT {
            out.push_size = out.push_size.max(module.push_size(name, ptr)?);
            continue;
        }
        let Some(&binding) = module.decorations.get(&(id, DEC_BINDING)) else {
            continue;
        };
        if module.decorations.get(&(id, DEC_SET)).copied().unwrap_or(0) != 0 {
            return Err(Error::Spirv(name, "only descriptor set 0 is supported".into()));
        }
        let kind = module.descriptor_type(name, (id, ptr, class), binding)?;
        out.bindings.push(Binding {
            slot: binding,
            kind,
            name: module.binding_name(name, (id, ptr), binding)?,
        });
    }
    out.bindings.sort_by_key(|b| b.slot);
    for (i, b) in out.bindings.iter().enumerate() {
        if let Some(other) = out.bindings[..i].iter().find(|o| o.name == b.name) {
            let both = format!("bindings {} and {} are both named {}", other.slot, b.slot, b.name);
            return Err(Error::Spirv(name, both));
        }
    }
    // The named structs' member offsets and the arrays' strides, for layout checks.
    for (&id, (op, ops)) in &module.types {
        if *op == OP_TYPE_STRUCT {
            if let Some(struct_name) = module.names.get(&id) {
                let members = (0..ops.len() as u32)
                    .filter_map(|m| {
                        let offset = module.member_offsets.get(&(id, m))?;
                        Some((module.member_names.get(&(id, m)).cloned().unwrap_or_default(), *offset))
                    })
                    .collect::<Vec<_>>();
                if members.len() == ops.len() {
                    out.structs.insert(struct_name.clone(), members);
                }
            }
        }
        if matches!(*op, OP_TYPE_ARRAY | OP_TYPE_RUNTIME_ARRAY) {
            if let (Some(elem_name), Some(&stride)) = (
                module.names.get(&ops[0]),
                module.decorations.get(&(id, DEC_ARRAY_STRIDE)),
            ) {
                out.array_strides.insert(elem_name.clone(), stride);
            }
        }
    }
    Ok(out)
}

/// Bytes of a scalar, vector or matrix type (the types push constants hold here).
fn scalar_size(types: &HashMap<u32, (u32, Vec<u32>)>, ty: u32) -> Option<u32> {
    match types.get(&ty)? {
        (OP_TYPE_BOOL, _) => Some(4),
        (OP_TYPE_INT | OP_TYPE_FLOAT, ops) => Some(ops.first()? / 8),
        (OP_TYPE_VECTOR | OP_TYPE_MATRIX, ops) => Some(scalar_size(types, *ops.first()?)? * ops.get(1)?),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rejects_non_spirv_bytes() {
        assert!(words("x", &[1, 2, 3]).is_err());
        assert!(words("x", &[0u8; 24]).is_err(), "wrong magic");
    }

    #[test]
    fn rejects_truncated_instruction() {
        // Header, then an instruction claiming 9 words with only 1 present.
        let module = [MAGIC, 0x0001_0500, 0, 10, 0, (9 << 16) | OP_NAME];
        assert!(reflect("x", &module).is_err());
    }
}
