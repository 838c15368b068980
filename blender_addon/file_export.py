"""What the add-on's File > Export operators share: the file browser, the report, the menu."""
import bpy


class ExportOperator:
    """Mixin for an export operator: the subclass sets ``menu_label``, ``errors`` (what a
    failed write raises) and ``write(context, path)``; this runs the file browser and reports."""

    menu_label = ""
    errors = (OSError, ValueError)

    def write(self, context, path):
        raise NotImplementedError

    def execute(self, context):
        path = bpy.path.abspath(self.filepath)
        try:
            self.write(context, path)
        except self.errors as exc:
            self.report({"ERROR"}, f"ThinBurn: {exc}")
            return {"CANCELLED"}
        self.report({"INFO"}, f"ThinBurn: wrote {path}")
        return {"FINISHED"}

    def invoke(self, context, event):
        context.window_manager.fileselect_add(self)
        return {"RUNNING_MODAL"}


def registrar(cls):
    """(register, unregister) for one export operator and its File > Export entry."""
    def menu(self, context):
        self.layout.operator(cls.bl_idname, text=cls.menu_label)
    menu.__module__ = cls.__module__  # the entry belongs to the operator's module

    def register():
        bpy.utils.register_class(cls)
        bpy.types.TOPBAR_MT_file_export.append(menu)

    def unregister():
        bpy.types.TOPBAR_MT_file_export.remove(menu)
        bpy.utils.unregister_class(cls)
    return register, unregister
