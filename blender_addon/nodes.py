"""Small helpers to build node groups, materials and modifiers from Python."""
from __future__ import annotations

import bpy


def socket(sockets, key):
    """A socket by identifier, else by name (first available one)."""
    for s in sockets:
        if s.identifier == key:
            return s
    for s in sockets:
        if s.name == key and s.enabled:
            return s
    raise KeyError(key)


def node(tree, kind, x, y, **attrs):
    node = tree.nodes.new(kind)
    node.location = (x, y)
    for k, v in attrs.items():
        setattr(node, k, v)
    return node


def link(tree, out_node, out_key, in_node, in_key):
    tree.links.new(socket(out_node.outputs, out_key), socket(in_node.inputs, in_key))


def set_input(node, key, value):
    socket(node.inputs, key).default_value = value


def new_group(name, kind):
    old = bpy.data.node_groups.get(name)
    if old is not None:
        return old, False
    return bpy.data.node_groups.new(name, kind), True


def interface_socket(tree, name, in_out, socket_type, default=None, lo=None, hi=None, desc=""):
    s = tree.interface.new_socket(name, in_out=in_out, socket_type=socket_type, description=desc)
    if default is not None:
        s.default_value = default
    if lo is not None:
        s.min_value = lo
    if hi is not None:
        s.max_value = hi
    return s


def map_range(tree, x, y, value, lo, hi, clamp=True, interp="LINEAR"):
    """MapRange(value from [lo, hi] to [0, 1]); each argument is (node, socket) or a number."""
    n = node(tree, "ShaderNodeMapRange", x, y, clamp=clamp, interpolation_type=interp)
    for key, src in (("Value", value), ("From Min", lo), ("From Max", hi)):
        if isinstance(src, tuple):
            link(tree, src[0], src[1], n, key)
        else:
            set_input(n, key, src)
    return n


def use_nodes(mat):
    if mat.node_tree is None:  # Blender < 5.0 starts materials without nodes
        mat.use_nodes = True


def ensure_modifier(obj, name, kind, index):
    md = obj.modifiers.get(name)
    if md is not None and md.type != kind:
        obj.modifiers.remove(md)
        md = None
    if md is None:
        md = obj.modifiers.new(name, kind)
    current = list(obj.modifiers).index(md)
    if current != index:
        obj.modifiers.move(current, index)
    return md
