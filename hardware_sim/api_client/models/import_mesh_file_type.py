from enum import StrEnum

class ImportMeshFileType(StrEnum):
    GLB = "glb"
    OBJ = "obj"
    OFF = "off"
    PLY = "ply"
    STL = "stl"

    def __str__(self) -> str:
        return str(self.value)
