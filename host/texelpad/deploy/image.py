"""texelpad.image under the name it had before it moved below deploy and
firmware (issue 33): ../shared/instruments/cpyemu/make-texel-fs.sh imports
`texelpad.deploy.image`. The same module object, not a copy."""
import sys

from .. import image as _image

sys.modules[__name__] = _image
