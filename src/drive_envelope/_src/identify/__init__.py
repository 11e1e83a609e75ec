"""System identification: estimate a stand's envelope, drive, friction and armature from bench logs."""
